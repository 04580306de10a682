"""The catalog's gripper grasps: where the parallel gripper closes on each part.

The grasps are the sim's alone (the recognizer never grasps), so psorr's catalog
(:mod:`psorr.synthetic.catalog`) reads each part's mesh, mass, colour and symmetries from
``catalog.json`` and this module reads the same file's ``"grasps"`` lists. Units are metres; points
and directions are in the part's model frame (origin at the centre of the resting face, +z up).
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np

from psorr.synthetic.catalog import DEFAULT_CATALOG
from sim.errors import GraspCatalogError, SimInputError

_PERPENDICULAR_TOL = 1e-6  # |approach . closing|, and |length - 1| of each direction
_REBUILD = "rebuild it with: python assets/workpieces/build_workpieces.py"


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


def load_grasps(path=DEFAULT_CATALOG) -> Mapping[str, tuple[Grasp, ...]]:
    """Part name -> its grasps, in catalog order (a part the catalog lists without grasps has none).

    Read once per catalog path and process; the result is read-only.

    Raises:
        GraspCatalogError: the file is missing or not JSON, or a grasp entry is incomplete or invalid.
    """
    return _grasps_of_catalog(str(Path(path).resolve()))


@functools.lru_cache(maxsize=8)
def _grasps_of_catalog(path: str) -> Mapping[str, tuple[Grasp, ...]]:
    try:
        parts = json.loads(Path(path).read_text(encoding="utf-8"))["parts"]
        entries = {name: entry.get("grasps", []) for name, entry in parts.items()}
    except FileNotFoundError:
        raise GraspCatalogError(path, "catalog file not found", f"check the path, or {_REBUILD}") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, AttributeError) as exc:
        raise GraspCatalogError(path, f"has no 'parts' object to read grasps from: {exc}", _REBUILD) from None
    grasps = {}
    for name, entries_of_part in entries.items():
        try:
            grasps[name] = tuple(Grasp(g["name"], g["point"], g["approach"], g["closing"], g["width"])
                                 for g in entries_of_part)
        except KeyError as exc:
            raise GraspCatalogError(path, f"a grasp of part {name!r} lacks the key {exc}", _REBUILD) from None
        except (TypeError, SimInputError) as exc:
            raise GraspCatalogError(path, f"part {name!r} has a malformed grasp: {exc}", _REBUILD) from None
    return MappingProxyType(grasps)


def grasp_named(part: str, name: str, path=DEFAULT_CATALOG) -> Grasp:
    """The grasp ``name`` of ``part``; SimInputError naming the valid parts, or the part's grasps, otherwise."""
    grasps = load_grasps(path)
    if part not in grasps:
        raise SimInputError(f"unknown workpiece {part!r}; choose one of {sorted(grasps)}")
    for grasp in grasps[part]:
        if grasp.name == name:
            return grasp
    raise SimInputError(f"{part} has no grasp {name!r}; choose one of {[g.name for g in grasps[part]]}")
