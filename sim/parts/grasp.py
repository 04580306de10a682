"""A parallel-gripper grasp of a part: :class:`Grasp`, in the part's model frame.

Units are metres; points and directions are in the part's model frame (origin at the centre of the
resting face, +z up). The catalog's grasps are read by :mod:`sim.skills.grasps`; a user's part gets
grasps synthesised from its mesh (:mod:`sim.parts.grasp_synthesis`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.errors import SimInputError

_PERPENDICULAR_TOL = 1e-6  # |approach . closing|, and |length - 1| of each direction


def _model_vector(value, what: str, unit: bool) -> np.ndarray:
    """``value`` as a read-only (3,) float64 copy, refused unless 3 finite numbers (of length 1 if ``unit``)."""
    try:
        vector = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise SimInputError(f"{what} must be 3 numbers (x, y, z), got {value!r}") from None
    if vector.shape != (3,) or not np.isfinite(vector).all():
        raise SimInputError(f"{what} must be 3 finite numbers (x, y, z), got {value!r}")
    if unit and abs(float(np.linalg.norm(vector)) - 1.0) > _PERPENDICULAR_TOL:
        raise SimInputError(f"{what} must be a unit vector, got length {np.linalg.norm(vector):.6g}")
    vector.setflags(write=False)
    return vector


@dataclass(frozen=True, eq=False)
class Grasp:
    """A parallel-gripper grasp in the model frame.

    Attributes:
        name: label, unique within the part.
        point: (3,) metres, the centre between the fingertips when closed.
        approach: (3,) unit vector the gripper travels along towards the part ((0, 0, -1): from above).
        closing: (3,) unit vector along which the fingers close, perpendicular to ``approach``.
        width: metres between the two parallel faces the fingers close on.
    """

    name: str
    point: np.ndarray
    approach: np.ndarray
    closing: np.ndarray
    width: float

    def __post_init__(self):
        label = f"grasp {self.name!r}"
        object.__setattr__(self, "point", _model_vector(self.point, f"{label} point", unit=False))
        object.__setattr__(self, "approach", _model_vector(self.approach, f"{label} approach", unit=True))
        object.__setattr__(self, "closing", _model_vector(self.closing, f"{label} closing", unit=True))
        if abs(float(self.approach @ self.closing)) > _PERPENDICULAR_TOL:
            raise SimInputError(f"{label}: closing must be perpendicular to approach")
        width = self.width
        if isinstance(width, bool) or not isinstance(width, (int, float)) or not math.isfinite(width) or width <= 0:
            raise SimInputError(f"{label} width must be a positive number of metres, got {width!r}")
        object.__setattr__(self, "width", float(width))

    def as_record(self) -> dict:
        """The grasp as JSON-ready numbers (read back by :meth:`from_record`)."""
        return {"name": self.name, "point": self.point.tolist(), "approach": self.approach.tolist(),
                "closing": self.closing.tolist(), "width": self.width}

    @classmethod
    def from_record(cls, record: dict) -> Grasp:
        """The grasp :meth:`as_record` wrote; KeyError or SimInputError when the record is not one."""
        return cls(record["name"], record["point"], record["approach"], record["closing"], record["width"])
