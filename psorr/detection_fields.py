"""The values a :class:`~psorr.types.Detection` carries beside its pose: the colour of the segment it was
found in, and what the view left open (other models' poses, a turn about the model's axis)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.checks.arrays import frozen_array, not_unit, rigid_pose, unit_share
from psorr.errors import InvalidInputError


@dataclass(frozen=True)
class DetectionColour:
    """The colour of the segment a detection was found in: ``name`` from psorr.segment's palette and
    ``mean_rgb`` (r, g, b) in [0, 1]."""

    name: str
    mean_rgb: tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class Rival:
    """Another library ``model``'s pose ``T_cloud_model`` (4, 4: model metres into the cloud's frame) over a
    detection's pixels that the view could not rule out: rendered, the two agree with the measured depth
    alike (a cable clip and its variant for a thicker sleeve differ inside a channel the sensor does not
    see into). ``score`` in [0, 1], as :attr:`Detection.score`; the detection kept explained more."""

    model: str
    T_cloud_model: np.ndarray
    score: float

    def __post_init__(self):
        object.__setattr__(self, "T_cloud_model", rigid_pose(self.T_cloud_model, "Rival.T_cloud_model"))
        object.__setattr__(self, "score", unit_share(self.score, "Rival.score"))


@dataclass(frozen=True, eq=False)
class UnfixedTurn:
    """A turn a detection's view left open: the model turned by any angle about the line through ``point``
    (3,) along the unit ``direction`` (3,), both in the model's frame (metres), fits the view as the detection
    does (a pulley round but for a keyway in its bore, the bore facing away)."""

    point: np.ndarray
    direction: np.ndarray

    def __post_init__(self):
        for name in ("point", "direction"):
            value = getattr(self, name)
            object.__setattr__(self, name, frozen_array([value] if np.ndim(value) == 1 else value,
                                                        f"UnfixedTurn.{name}", np.float64, (3,), 1)[0])
        if not_unit(self.direction[None])[0]:
            raise InvalidInputError("UnfixedTurn.direction must be a unit vector: divide it by its norm")
