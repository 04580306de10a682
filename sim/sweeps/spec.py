"""Sweep files (``tasks/sweeps/*.yaml``): a grid of seeded episodes.

::

    tasks: [../demo.yaml]            # task files, relative to the sweep file
    seeds: 10                        # seeds 0..9, or a list of seeds (default: seed 0)
    poses: [recognized, oracle]      # pose sources (default: recognized)
    camera_height: [0.7, 0.9]        # m above the table (default: each task's own)
    resolution: [640x480, 320x240]   # the Kinect's image (default: 640x480); the field of view is kept
    occluder: true                   # the person reaches in (default true)
    noise: [1, 2]                    # the Kinect v1's axial depth noise times this (default 1)
    method: [psorr, orr]             # the recognizer (default psorr; psg, auto, orr)

The grid is every combination; each combination is one :class:`EpisodeSpec`, named by its values.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass
from pathlib import Path

from psorr.recognize import Method
from sim.errors import TaskFileError
from sim.modes import PoseSource
from sim.skills.perception_params import PerceptionParams
from sim.world.tasks import load_task, read_lined_yaml

SWEEP_KEYS = ("tasks", "seeds", "poses", "camera_height", "resolution", "occluder", "noise", "method")
_EXAMPLE = "see tasks/sweeps/smoke.yaml"


@dataclass(frozen=True)
class EpisodeSpec:
    """One episode of a sweep: everything that makes it, so that a worker anywhere can run it."""

    task: str
    seed: int
    poses: str
    camera_height: float | None
    resolution: str
    occluder: bool
    noise: float = 1.0
    method: str = Method.PSORR.value

    @property
    def id(self) -> str:
        height = "task" if self.camera_height is None else f"{self.camera_height:g}"
        return (f"{Path(self.task).stem}-{self.poses}-h{height}-{self.resolution}-occ{int(self.occluder)}"
                f"-n{self.noise:g}-{self.method}-s{self.seed}")

    @property
    def perception(self) -> PerceptionParams:
        """The looks' recognizer and noise level."""
        return PerceptionParams(method=self.method, noise_scale=self.noise)

    def world_config(self):
        """The task's WorldConfig with this episode's camera and person."""
        config = dataclasses.replace(load_task(self.task).world, occluder=self.occluder)
        if self.camera_height is not None:
            config = dataclasses.replace(config, camera_height=self.camera_height)
        width, height = (int(v) for v in self.resolution.split("x"))
        if (width, height) != config.intrinsics.shape[::-1]:
            scale = width / config.intrinsics.width
            intrinsics = dataclasses.replace(config.intrinsics, width=width, height=height,
                                             fx=config.intrinsics.fx * scale, fy=config.intrinsics.fy * scale,
                                             cx=(width - 1) / 2, cy=(height - 1) / 2)
            config = dataclasses.replace(config, intrinsics=intrinsics)
        return config


@dataclass(frozen=True)
class Sweep:
    """A parsed sweep file and its grid of episodes, in a fixed order."""

    path: Path
    episodes: tuple[EpisodeSpec, ...]
    swept: tuple[str, ...]  # the variables given more than one value


def load_sweep(path) -> Sweep:
    """Read a sweep file; a bad key or value raises TaskFileError naming its line and the fix."""
    path = Path(path)
    spec = read_lined_yaml(path, "sweep", _EXAMPLE)
    if not isinstance(spec, dict) or "tasks" not in spec:
        raise TaskFileError(path, "a sweep must be a mapping with tasks:", _EXAMPLE)
    for key in spec:
        if key not in SWEEP_KEYS:
            raise TaskFileError(path, f"line {spec.lines[key]}: unknown key {key!r}",
                                f"valid keys are {', '.join(SWEEP_KEYS)}")
    values = {key: _values(path, spec, key) for key in SWEEP_KEYS}
    episodes = tuple(EpisodeSpec(*combo) for combo in itertools.product(*values.values()))
    swept = tuple(k for k, v in values.items() if len(v) > 1)
    return Sweep(path, episodes, swept)


def _values(path: Path, spec, key: str) -> list:
    given = spec.get(key)
    line = spec.lines.get(key, 0)

    def bad(what: str):
        return TaskFileError(path, f"line {line}: {key} {what}", _EXAMPLE)

    if key == "tasks":
        if not isinstance(given, list) or not given or not all(isinstance(t, str) for t in given):
            raise bad("must be a list of task files")
        tasks = [str((path.parent / t).resolve()) for t in given]
        for task in tasks:
            load_task(task)  # a bad task is refused now, not in a worker an hour in
        return tasks
    if key == "seeds":
        given = 1 if given is None else given
        seeds = list(range(given)) if isinstance(given, int) and not isinstance(given, bool) else given
        if not isinstance(seeds, list) or not seeds or not all(
                isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds):
            raise bad("must be a count of seeds or a list of seeds >= 0")
        return seeds
    defaults = {"poses": [PoseSource.RECOGNIZED.value], "camera_height": [None], "resolution": ["640x480"],
                "occluder": [True], "noise": [1.0], "method": [Method.PSORR.value]}
    if given is None:
        return defaults[key]
    items = given if isinstance(given, list) else [given]
    for item in items:
        _check(key, item, bad)
    return [float(i) if key in ("camera_height", "noise") else i for i in items]


def _check(key: str, item, bad) -> None:
    if key == "poses" and item not in [p.value for p in PoseSource]:
        raise bad(f"must be among {', '.join(p.value for p in PoseSource)}, got {item!r}")
    if key == "camera_height" and (isinstance(item, bool) or not isinstance(item, (int, float))
                                   or not 0.6 <= item <= 1.0):
        raise bad(f"must be metres in [0.6, 1.0], got {item!r}")
    if key == "resolution":
        parts = item.split("x") if isinstance(item, str) else []
        if len(parts) != 2 or not all(p.isdigit() and int(p) >= 80 for p in parts) \
                or int(parts[0]) * 3 != int(parts[1]) * 4:
            raise bad(f"must be WIDTHxHEIGHT at the Kinect's 4:3, such as 320x240, got {item!r}")
    if key == "occluder" and not isinstance(item, bool):
        raise bad(f"must be true or false, got {item!r}")
    if key == "noise" and (isinstance(item, bool) or not isinstance(item, (int, float)) or not 0 <= item <= 10):
        raise bad(f"must be a multiple of the Kinect v1's depth noise in [0, 10], got {item!r}")
    if key == "method" and item not in [m.value for m in Method]:
        raise bad(f"must be among {', '.join(m.value for m in Method)}, got {item!r}")

