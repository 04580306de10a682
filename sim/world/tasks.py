"""Task files for `psorr-sim run`: which workpieces go on the table, and the camera."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from sim.errors import SimInputError, TaskFileError
from sim.world.config import WorldConfig

TASK_KEYS = ("workpieces", "camera_height", "camera_tilt_deg")


@dataclass(frozen=True)
class Task:
    """A parsed task: its file and the world it asks for."""

    path: Path
    world: WorldConfig


def load_task(path) -> Task:
    """Read a YAML task; bad files and unknown keys or parts raise an error naming the file and the fix."""
    import yaml

    from psorr.synthetic.catalog import load_catalog

    path = Path(path)
    if path.is_dir():
        raise TaskFileError(path, "is a folder, not a task file", "pass a .yaml task in it, such as tasks/demo.yaml")
    if not path.is_file():
        raise TaskFileError(path, "no such task file", "see tasks/demo.yaml for the format")
    try:
        spec = yaml.load(path.read_text(encoding="utf-8"), Loader=_unique_key_loader())
    except UnicodeDecodeError:
        raise TaskFileError(path, "not UTF-8 text", "save the task file as UTF-8 YAML") from None
    except yaml.YAMLError as exc:
        where = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        at = f", line {where.line + 1}" if where is not None else ""
        problem = getattr(exc, "problem", None) or exc.__class__.__name__
        raise TaskFileError(path, f"not valid YAML ({problem}{at})", "fix the syntax") from None
    if not isinstance(spec, dict):
        raise TaskFileError(path, "a task must be a mapping", f"give the keys {', '.join(TASK_KEYS)}")
    unknown = sorted(set(spec) - set(TASK_KEYS))
    if unknown:
        raise TaskFileError(path, f"unknown keys {unknown}", f"valid keys are {', '.join(TASK_KEYS)}")
    parts = spec.get("workpieces")
    catalog = load_catalog()
    if not isinstance(parts, list) or not parts or not all(isinstance(p, str) for p in parts):
        raise TaskFileError(path, "workpieces must be a non-empty list of part names",
                             f"choose from {', '.join(sorted(catalog))}")
    missing = sorted(set(parts) - set(catalog))
    if missing:
        raise TaskFileError(path, f"unknown workpieces {missing}", f"choose from {', '.join(sorted(catalog))}")
    options = {}
    for key in ("camera_height", "camera_tilt_deg"):
        if key in spec:
            value = spec[key]
            # YAML reads `true` as a bool, which float() would take for 1.0.
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise TaskFileError(path, f"{key} must be a number, got {value!r}", "see tasks/demo.yaml")
            options[key] = float(value)
    try:
        return Task(path, WorldConfig(workpieces=tuple(parts), **options))
    except SimInputError as exc:  # a value out of range, or a part listed twice: this file's fault
        raise TaskFileError(path, str(exc)) from None


def _unique_key_loader():
    """A safe YAML loader that refuses a key given twice in one mapping, which PyYAML would take silently,
    keeping the last value (a task listing `occluder:` twice ran with whichever came second)."""
    import yaml

    class Loader(yaml.SafeLoader):
        def construct_mapping(self, node, deep=False):
            seen = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=deep)
                if key in seen:
                    raise yaml.constructor.ConstructorError(None, None, f"the key {key!r} is given twice",
                                                            key_node.start_mark)
                seen.add(key)
            return super().construct_mapping(node, deep)

    return Loader
