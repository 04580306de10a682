"""Task files for `psorr-sim run`: which workpieces go on the table, how they rest, and the camera.

A workpiece is a catalog part's name, or a mapping that names a mesh of the user's own::

    workpieces:
      - chassis                     # a catalog part
      - mesh: parts/idler.stl       # relative paths are from the task file
        units: mm                   # m (default), cm, mm or in
        name: idler                 # default: the file stem
        count: 2                    # instances (default 1): bodies idler_1 and idler_2
        color: [0.8, 0.2, 0.2]      # optional RGB in [0, 1]
        density: 1240               # kg/m^3 (default: printed PLA's)
        place: tote                 # fixture or tote (default: as the part rests)
    resting: any                    # upright (default): each part on its largest stable face, placed in a
                                    # fixture; any: each in a seeded random stable rest, placed in the tote
    min_gap: 0.0                    # m between footprints (default 0.02); 0 lets parts touch
    pick: [red idler]               # which parts to pick, in order, each by name and optionally by the colour
                                    # the robot sees it in (default: every part, in task order)
    reach_gap: [0.5, 2.0]           # seconds the person waits between reaches, min and max (default [2, 8])

Every key is checked before the world is built, and a wrong one is named with its line.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from sim.errors import SimInputError, TaskFileError
from sim.parts.source import MeshPart
from sim.world.config import RESTING, WorldConfig

TASK_KEYS = ("workpieces", "camera_height", "camera_tilt_deg", "resting", "min_gap", "pick", "reach_gap")
MESH_KEYS = ("mesh", "units", "name", "count", "color", "density", "place")
_EXAMPLE = "see tasks/demo.yaml and tasks/printed_parts.yaml"


@dataclass(frozen=True)
class Task:
    """A parsed task: its file and the world it asks for."""

    path: Path
    world: WorldConfig


class _Lined(dict):
    """A YAML mapping that remembers the line of each key (1-based) in ``lines``, and its own in ``line``."""

    line: int = 0
    lines: dict


class _LinedList(list):
    """A YAML sequence that remembers the line of each item (1-based) in ``lines``."""

    lines: list


def load_task(path) -> Task:
    """Read a YAML task; bad files, keys, parts or meshes raise an error naming the file, the line and the fix."""
    path = Path(path)
    spec = _read(path)
    if not isinstance(spec, dict):
        raise TaskFileError(path, "a task must be a mapping", f"give the keys {', '.join(TASK_KEYS)}")
    for key in spec:
        if key not in TASK_KEYS:
            raise TaskFileError(path, f"line {spec.lines[key]}: unknown key {key!r}",
                                f"valid keys are {', '.join(TASK_KEYS)}")
    names, meshes = _workpieces(path, spec)
    options = {}
    for key, field in (("camera_height", "camera_height"), ("camera_tilt_deg", "camera_tilt_deg"), ("min_gap", "gap")):
        if key in spec:
            options[field] = _number(path, spec, key)
    resting = spec.get("resting", "upright")
    if resting not in RESTING:
        raise TaskFileError(path, f"line {spec.lines['resting']}: resting must be one of {', '.join(RESTING)}, "
                            f"got {resting!r}")
    if "pick" in spec:
        options["pick"] = _pick(path, spec)
    if "reach_gap" in spec:
        options["reach_gap_s"] = _reach_gap(path, spec)
    try:
        return Task(path, WorldConfig(workpieces=names, mesh_parts=meshes, resting=resting, **options))
    except SimInputError as exc:  # a value out of range, or a part listed twice: this file's fault
        key = next((k for k in spec if str(exc).startswith(k)), None)
        raise TaskFileError(path, str(exc) if key is None else f"line {spec.lines[key]}: {exc}") from None


def _read(path: Path):
    return read_lined_yaml(path, "task", _EXAMPLE)


def read_lined_yaml(path: Path, kind: str, example: str):
    """A task, plan or sweep file (``kind``) read with :func:`lined_loader`; a folder, a missing file, bytes
    that are not UTF-8 or broken YAML raise TaskFileError naming the file and the fix (``example``)."""
    import yaml

    if path.is_dir():
        raise TaskFileError(path, f"is a folder, not a {kind} file", f"pass a .yaml {kind} file; {example}")
    if not path.is_file():
        raise TaskFileError(path, f"no such {kind} file", example)
    try:
        return yaml.load(path.read_text(encoding="utf-8"), Loader=lined_loader())
    except UnicodeDecodeError:
        raise TaskFileError(path, "not UTF-8 text", f"save the {kind} file as UTF-8 YAML") from None
    except yaml.YAMLError as exc:
        where = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        at = f", line {where.line + 1}" if where is not None else ""
        problem = getattr(exc, "problem", None) or exc.__class__.__name__
        raise TaskFileError(path, f"not valid YAML ({problem}{at})", "fix the syntax") from None


def _number(path: Path, spec: _Lined, key: str) -> float:
    value = spec[key]
    # YAML reads `true` as a bool, which float() would take for 1.0.
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TaskFileError(path, f"line {spec.lines[key]}: {key} must be a number, got {value!r}", _EXAMPLE)
    return float(value)


def _pick(path: Path, spec: _Lined) -> tuple[str, ...]:
    pick = spec["pick"]
    if isinstance(pick, str):
        pick = [pick]
    if not isinstance(pick, list) or not pick or not all(isinstance(p, str) for p in pick):
        raise TaskFileError(path, f"line {spec.lines['pick']}: pick must be a list of parts, each optionally after "
                            f"its colour, as in [red idler, chassis]; got {spec['pick']!r}")
    return tuple(pick)


def _reach_gap(path: Path, spec: _Lined) -> tuple[float, float]:
    gap = spec["reach_gap"]
    if not isinstance(gap, list) or len(gap) != 2 or not all(
            isinstance(g, (int, float)) and not isinstance(g, bool) for g in gap) or not 0 < gap[0] <= gap[1]:
        raise TaskFileError(path, f"line {spec.lines['reach_gap']}: reach_gap must be [min, max] seconds between "
                            f"the person's reaches, with 0 < min <= max, such as [0.5, 2.0]; got {gap!r}")
    return float(gap[0]), float(gap[1])


def _workpieces(path: Path, spec: _Lined) -> tuple[tuple[str, ...], tuple[MeshPart, ...]]:
    """(every part's name in task order, the mesh parts among them), each entry checked."""
    from psorr.synthetic.catalog import load_catalog

    entries, catalog = spec.get("workpieces"), load_catalog()
    choices = f"name catalog parts ({', '.join(sorted(catalog))}) or meshes (mesh: FILE); {_EXAMPLE}"
    if not isinstance(entries, list) or not entries:
        raise TaskFileError(path, "workpieces must be a non-empty list", choices)
    names, meshes = [], []
    for entry, line in zip(entries, entries.lines):
        if isinstance(entry, dict):
            part = _mesh_part(path, entry)
            if part.name in catalog:
                raise TaskFileError(path, f"line {line}: the mesh part's name {part.name!r} is a catalog part's",
                                    "give it another name with name:")
            names.append(part.name)
            meshes.append(part)
        elif isinstance(entry, str) and entry in catalog:
            names.append(entry)
        else:
            raise TaskFileError(path, f"line {line}: unknown workpiece {entry!r}", choices)
    return tuple(names), tuple(meshes)


def _mesh_part(path: Path, entry: _Lined) -> MeshPart:
    for key in entry:
        if key not in MESH_KEYS:
            raise TaskFileError(path, f"line {entry.lines[key]}: unknown key {key!r} in a mesh workpiece",
                                f"valid keys are {', '.join(MESH_KEYS)}")
    if "mesh" not in entry or not isinstance(entry["mesh"], str):
        raise TaskFileError(path, f"line {entry.line}: a mesh workpiece needs mesh: FILE (a path to an STL, OBJ, "
                            "PLY or STEP file)", _EXAMPLE)
    mesh = (path.parent / entry["mesh"]).resolve()
    if not mesh.is_file():
        raise TaskFileError(path, f"line {entry.lines['mesh']}: no mesh file {mesh}",
                            "give its path relative to the task file")
    values = {key: entry[key] for key in MESH_KEYS[1:] if key in entry}
    try:
        part = MeshPart(mesh, **values)
    except SimInputError as exc:
        key = next((k for k in values if str(exc).startswith(k)), "mesh")
        raise TaskFileError(path, f"line {entry.lines[key]}: {exc}") from None
    return part


def lined_loader():
    """A safe YAML loader whose mappings and sequences remember their lines, and that refuses a key given twice
    in one mapping, which PyYAML would take silently, keeping the last value."""
    import yaml

    class Loader(yaml.SafeLoader):
        pass

    def mapping(loader, node):
        data = _Lined()
        data.line, data.lines = node.start_mark.line + 1, {}
        yield data
        for key_node, value_node in node.value:
            key = loader.construct_object(key_node, deep=True)
            if key in data.lines:
                raise yaml.constructor.ConstructorError(None, None, f"the key {key!r} is given twice",
                                                        key_node.start_mark)
            data.lines[key] = key_node.start_mark.line + 1
            data[key] = loader.construct_object(value_node, deep=True)

    def sequence(loader, node):
        data = _LinedList()
        data.lines = [item.start_mark.line + 1 for item in node.value]
        yield data
        data.extend(loader.construct_object(item, deep=True) for item in node.value)

    Loader.add_constructor("tag:yaml.org,2002:map", mapping)
    Loader.add_constructor("tag:yaml.org,2002:seq", sequence)
    return Loader
