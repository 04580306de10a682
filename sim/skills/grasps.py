"""The catalog's gripper grasps: where the parallel gripper closes on each part.

The grasps are the sim's alone (the recognizer never grasps), so psorr's catalog
(:mod:`psorr.synthetic.catalog`) reads each part's mesh, mass, colour and symmetries from
``catalog.json`` and this module reads the same file's ``"grasps"`` lists. Units are metres; points
and directions are in the part's model frame (origin at the centre of the resting face, +z up).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType

from psorr.synthetic.catalog import DEFAULT_CATALOG
from sim.errors import GraspCatalogError, SimInputError
from sim.parts.grasp import Grasp

_REBUILD = "rebuild it with: python assets/workpieces/build_workpieces.py"


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
