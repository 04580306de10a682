"""Oriented boxes for the box tests: one from a centre, sides and rotation, and seeded random ones."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from psorr.types import OrientedBox


def box(center=(0, 0, 0), extent=(1, 1, 1), rotation=None) -> OrientedBox:
    rotation = np.eye(3) if rotation is None else rotation
    return OrientedBox(np.asarray(center, float), rotation, np.asarray(extent, float))


def random_box(rng, spread=0.3, size=(0.05, 1.0)) -> OrientedBox:
    return box(rng.uniform(-spread, spread, 3), rng.uniform(*size, 3), Rotation.random(random_state=rng).as_matrix())
