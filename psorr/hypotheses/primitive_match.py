"""Could a scene primitive be (part of) a model primitive? Kind and size say no to most pairs.

A pair-feature lookup compares only the angles and the distance of two oriented points. So
a scene cylinder's axis matches a model plane's normal, and a 4 cm face matches a 12 cm
wall's samples, whenever the angles agree; in a cluttered scene such chance matches outvote
a part that shows only two or three primitives. A seen face can be cut down by occlusion
but can never be larger than its model face, and a cylinder keeps its radius, so matches
that break either are dropped before the votes are counted.
"""

from __future__ import annotations

import numpy as np

from psorr.hypotheses.single_plane import in_plane_sides
from psorr.types import Primitive, PrimitiveKind

RADIUS_TOLERANCE = 0.3  # a scene cylinder's radius within 30 % of the model's (box verification asks the same)
SIDE_RATIO = 1.2        # a scene face's sides at most this times the model face's ...
SIDE_SLACK = 0.01       # ... plus this many metres: boxes of noisy points grow by a few millimetres


def _shape(p: Primitive) -> tuple[bool, np.ndarray]:
    """(is a cylinder, size): a cylinder's radius, or a plane's two in-plane box sides (metres)."""
    if p.kind is PrimitiveKind.CYLINDER:
        return True, np.array([p.radius, 0.0])
    return False, in_plane_sides(p)


class PrimitiveSizes:
    """Kinds and sizes of every primitive of a list of models, indexed (model, primitive) -> global."""

    def __init__(self, models):
        self.offsets = np.cumsum([0] + [len(m.graph.primitives) for m in models])
        shapes = [_shape(p) for m in models for p in m.graph.primitives]
        self.cylinder = np.array([c for c, _ in shapes], dtype=bool)
        self.size = np.array([s for _, s in shapes]).reshape(-1, 2)

    def compatible(self, scene_primitives) -> np.ndarray:
        """(S, G) bool: may scene primitive s be seen as (part of) model primitive g?"""
        shapes = [_shape(p) for p in scene_primitives]
        cylinder = np.array([c for c, _ in shapes], dtype=bool)
        size = np.array([s for _, s in shapes]).reshape(-1, 2)
        same_kind = cylinder[:, None] == self.cylinder[None, :]
        radius_ok = np.abs(size[:, None, 0] - self.size[None, :, 0]) <= RADIUS_TOLERANCE * self.size[None, :, 0]
        fits = (size[:, None, :] <= SIDE_RATIO * self.size[None, :, :] + SIDE_SLACK).all(axis=2)
        return same_kind & np.where(cylinder[:, None], radius_ok, fits)
