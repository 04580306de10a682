"""A user's mesh as a task file names it: :class:`MeshPart`, checked before anything is built."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from psorr.errors import PsorrError
from psorr.io.meshes import UNITS, file_units
from sim.errors import SimInputError

PLACES = ("fixture", "tote")
DEFAULT_DENSITY = 1240.0
"""kg/m^3 of a part that gives none: printed PLA, the material of most parts users bring from a printer."""
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_.-]*$")


@dataclass(frozen=True)
class MeshPart:
    """A part the cell takes from a mesh file rather than from the catalog.

    Attributes:
        path: the mesh file (STL, OBJ, PLY or STEP), absolute.
        units: the file's length unit: ``"m"``, ``"cm"``, ``"mm"`` or ``"in"``; None (the default) for the unit a
            STEP file declares, else metres. Given for a STEP file, it must be the one the file declares.
        name: the part's name in the cell and in the recognizer's library (default: the file's stem).
        count: how many of it go on the table.
        color: its colour: (3,) RGB in [0, 1] or a name of ``psorr.segment.PALETTE`` (``"red"``), for every
            instance, or a list of ``count`` of them, one per instance (two idlers, a red and a blue); None for
            a grey chosen from the name. Read back as the first instance's RGB, and every instance's in
            :attr:`instance_colors`.
        density: kg/m^3, for the mass and inertia.
        place: ``"fixture"``, ``"tote"``, or None for the task's default (a fixture for a part resting upright).
    """

    path: Path
    units: str | None = None
    name: str = ""
    count: int = 1
    color: tuple[float, float, float] | None = None
    density: float = DEFAULT_DENSITY
    place: str | None = None
    instance_colors: tuple[tuple[float, float, float], ...] | None = field(default=None, init=False)

    def __post_init__(self):
        object.__setattr__(self, "path", Path(self.path))
        if not self.name:
            object.__setattr__(self, "name", self.path.stem)
        if self.units is not None and self.units not in UNITS:
            raise SimInputError(f"units must be one of {', '.join(UNITS)}, got {self.units!r}")
        object.__setattr__(self, "units", _units(self.path, self.units))
        if not _NAME.match(self.name):
            raise SimInputError(f"name must start with a letter and hold only letters, digits, '_', '.' or '-' "
                                f"(it names bodies and files), got {self.name!r}")
        if isinstance(self.count, bool) or not isinstance(self.count, int) or self.count < 1:
            raise SimInputError(f"count must be a whole number of at least 1, got {self.count!r}")
        if self.color is not None:
            colors = _instance_colors(self.color, self.count)
            object.__setattr__(self, "color", colors[0])
            object.__setattr__(self, "instance_colors", colors)
        if isinstance(self.density, bool) or not isinstance(self.density, (int, float)) \
                or not math.isfinite(self.density) or self.density <= 0:
            raise SimInputError(f"density must be a positive number of kg/m^3, got {self.density!r}")
        if self.place is not None and self.place not in PLACES:
            raise SimInputError(f"place must be one of {', '.join(PLACES)}, got {self.place!r}")

    @property
    def scale(self) -> float:
        """Metres per unit of the file."""
        return UNITS[self.units]


def _units(path: Path, units: str | None) -> str:
    """The unit to read ``path`` in: the one a STEP file declares (which ``units`` must agree with), else
    ``units``, else metres."""
    if not path.is_file():  # said where the file is read
        return units or "m"
    try:
        return file_units(path, units) or "m"
    except PsorrError as exc:
        raise SimInputError(f"units: {exc}") from None


def _instance_colors(value, count: int) -> tuple[tuple[float, float, float], ...]:
    """One RGB per instance from a task's color: one colour for all, or a list of ``count`` colours."""
    if isinstance(value, (list, tuple)) and value and all(isinstance(v, (str, list, tuple)) for v in value):
        if len(value) != count:
            raise SimInputError(f"color lists {len(value)} colours for count {count}: give one colour for every "
                                f"instance, or a single colour for all, got {value!r}")
        return tuple(_rgb(v) for v in value)
    return (_rgb(value),) * count


def _rgb(value) -> tuple[float, float, float]:
    from psorr.segment.colour import PALETTE

    if isinstance(value, str):
        if value not in PALETTE:
            raise SimInputError(f"color {value!r} is not a palette name: give one of {', '.join(PALETTE)}, or 3 "
                                "numbers in [0, 1] (red, green, blue)")
        return PALETTE[value]
    try:
        rgb = np.array(value, dtype=float)
    except (TypeError, ValueError):
        rgb = np.full(1, np.nan)
    if isinstance(value, (str, bytes)) or rgb.shape != (3,) or not np.isfinite(rgb).all() \
            or rgb.min() < 0 or rgb.max() > 1:
        raise SimInputError(f"color must be 3 numbers in [0, 1] (red, green, blue), got {value!r}")
    return tuple(float(c) for c in rgb)
