"""STEP files (ISO 10303-21, ``.step``/``.stp``): the CAD exchange format most parts come in.

A STEP file holds exact surfaces, not triangles; OpenCASCADE tessellates them, through the optional
``cascadio`` package (``pip install 'psorr[step]'``) that trimesh loads STEP with. Unlike STL, OBJ and
PLY, a STEP file declares its length unit, so :func:`declared_units` reads it and a mesh read from it is
given in that unit, as the other formats' meshes are given in theirs.
"""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

from psorr.errors import CloudFileError, MissingExtraError
from psorr.io.clouds import require_file

STEP_SUFFIXES = (".step", ".stp")
STEP_EXTRA = "pip install 'psorr[step]'"

# Which unit a STEP length unit entity names: an SI unit's prefix, or a conversion-based unit's name.
_SI_PREFIXES = {"$": "m", ".CENTI.": "cm", ".MILLI.": "mm"}
_CONVERSION_NAMES = {"INCH": "in", "MILLIMETRE": "mm", "MILLIMETER": "mm", "CENTIMETRE": "cm",
                     "CENTIMETER": "cm", "METRE": "m", "METER": "m"}
_UNIT_CONTEXT = re.compile(r"GLOBAL_UNIT_ASSIGNED_CONTEXT\s*\(\s*\(([^)]*)\)", re.IGNORECASE)
_SI_LENGTH = re.compile(r"SI_UNIT\s*\(\s*(\$|\.\w+\.)\s*,\s*\.METRE\.\s*\)", re.IGNORECASE)
_CONVERSION = re.compile(r"CONVERSION_BASED_UNIT\s*\(\s*'([^']*)'", re.IGNORECASE)


def is_step(path) -> bool:
    """Whether ``path`` names a STEP file by its suffix."""
    return Path(path).suffix.lower() in STEP_SUFFIXES


def declared_units(path) -> str | None:
    """The length unit (a key of ``psorr.io.meshes.UNITS``: 'm', 'cm', 'mm' or 'in') a STEP file declares for
    its geometry; None for a file of another format, whose unit only its user knows.

    Raises:
        CloudFileError: the file declares no length unit, several that differ, or one psorr has no name for.
    """
    path = Path(path)
    if not is_step(path):
        return None
    require_file(path)
    stat = path.stat()
    return _declared_units(path, stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=64)
def _declared_units(path: Path, mtime_ns: int, size: int) -> str:
    """:func:`declared_units` of the file as it is (its time and size in the key): training asks before reading the
    mesh and the reader again, and the whole text is searched each time."""
    text = path.read_bytes().decode("latin-1")
    found = set()
    for refs in _UNIT_CONTEXT.findall(text):
        for ref in re.findall(r"#\d+", refs):
            entity = re.search(rf"{ref}\s*=(.*?);", text, re.DOTALL)
            if entity is not None and "LENGTH_UNIT" in entity.group(1).upper():
                found.add(_unit_name(path, entity.group(1)))
    if not found:
        raise CloudFileError(path, "declares no length unit (no GLOBAL_UNIT_ASSIGNED_CONTEXT naming a LENGTH_UNIT)",
                             "re-export it from the CAD tool, or export the part as STL and give its units")
    if len(found) > 1:
        raise CloudFileError(path, f"declares its lengths in several units ({', '.join(sorted(found))})",
                             "re-export the part in one unit")
    return found.pop()


def _unit_name(path: Path, entity: str) -> str:
    """The unit a STEP length unit entity's text names."""
    conversion = _CONVERSION.search(entity)
    if conversion is not None:
        name = conversion.group(1).strip().upper()
        if name in _CONVERSION_NAMES:
            return _CONVERSION_NAMES[name]
        raise CloudFileError(path, f"declares its lengths in {name.lower()!r}, which psorr does not read",
                             "re-export it in millimetres, centimetres, metres or inches")
    si = _SI_LENGTH.search(entity)
    if si is not None and si.group(1).upper() in _SI_PREFIXES:
        return _SI_PREFIXES[si.group(1).upper()]
    shown = " ".join(entity.split())[:80]
    raise CloudFileError(path, f"declares a length unit psorr does not read ({shown})",
                         "re-export it in millimetres, centimetres, metres or inches")


def load_step_scene(path: Path):
    """The trimesh scene OpenCASCADE tessellates a STEP file into, in metres (cascadio's default deflection:
    0.01 mm, or 0.5 rad on radii under 0.3 mm); a MissingExtraError naming the extra that installs it, or a
    CloudFileError when OpenCASCADE finds no shape in it."""
    try:
        import cascadio  # noqa: F401  (trimesh's STEP loader needs it)
    except ImportError:
        raise MissingExtraError(f"{path}: reading STEP needs OpenCASCADE's cascadio package, which is not "
                                f"installed: {STEP_EXTRA} (or export the part as STL)") from None
    import trimesh

    try:
        return trimesh.load_scene(path)
    except Exception as exc:  # noqa: BLE001  OpenCASCADE wrote no GLB: trimesh then fails to open it
        raise CloudFileError(path, f"OpenCASCADE found no shape to tessellate in it ({type(exc).__name__}): no solid "
                                   "or surface, or a damaged file",
                             "re-export the part's solid as STEP, or as STL") from None

