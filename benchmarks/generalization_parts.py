"""The generalization benchmark's parts: the fixed dev/test split of ../shared/cad/prusa_i3, what is known
about each part (its symmetries, class and size, found from its mesh), and the grading of detections.

The split. The 39 Prusa i3 MK3 printed parts at least 25 mm long (the longest side of their oriented
bounding box) were classed by :func:`psorr.synthetic.part_shapes.part_shape`, ordered by size within
each class, and dealt out in pairs, each pair's order drawn by ``numpy.random.default_rng(31)``, to
the smaller half; so both halves hold thin, freeform and prismatic parts of every size. The two
Heatbed cable clips are one part but for the sleeve's hole, so the 8 mm sleeve's clip then moved to
its twin's half, and y-belt-tensioner (prismatic, 25-50 mm) to the other. Automatic classing finds no
turned or flanged part among them (the Prusa parts are printed, not turned): the class table says so.
Tune on dev only; report both.

Any other folder (a user's own parts) is split by :func:`folder_split`: its parts at least 25 mm long,
ordered by the SHA-256 of their names, are dealt out in turn to dev and test, so that the halves are the
same on every machine and whatever order the files are listed in; or ``all`` takes every part as one half.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import trimesh

from psorr.geometry.rotations import turn_about_line
from psorr.synthetic.catalog import model_diameter
from psorr.synthetic.mesh_scenes import MeshScene, SceneKind
from psorr.synthetic.mesh_symmetry import MeshSymmetry, find_symmetries, match_detections, mesh_symmetric_add
from psorr.synthetic.part_shapes import PartShape, part_shape

MIN_LENGTH = 0.025  # m: the parts are those at least 25 mm long at true scale
SIZES = (("under 25 mm", MIN_LENGTH), ("25-50 mm", 0.05), ("50-100 mm", 0.1), ("over 100 mm", np.inf))
ADD_SHARE = 0.1  # a detection is correct within a symmetry-aware ADD of 0.1 x the model's diameter
ADD_SAMPLES = 1000
# An unfixed turn about an axis is tried every 5 degrees: at the axis reach r <= d / 2 a step moves a point by
# r x 0.087 < 0.05 d, half the ADD a detection is correct within.
UNFIXED_STEP_DEG = 5.0

DEV = ("Einsy-hinges", "Extruder-cable-clip", "Heatbed-cable-clip", "Heatbed-cable-clip_for_8mm_sleeve",
       "LCD-knob", "PSU-cover-MK3", "Spool-holder", "extruder-body", "extruder-idler", "extruder-idler-mmu2s",
       "fan-shroud", "fs-cover-mmu2s", "heatbed-cable-cover-clip", "lcd-supports", "rpi-zero-frame",
       "x-carriage-back", "x-end-idler", "y-belt-idler", "z-axis-bottom", "z-axis-top")
TEST = ("Einsy-base", "Einsy-doors", "LCD-cover-ORIGINAL-MK3", "cable-holder", "extruder-cover",
        "extruder-motor-plate", "fs-cover", "heatbed-cable-cover", "ir-sensor-cover-mmu2s", "ir-sensor-holder-mmu2s",
        "print-fan-support", "psu-cover-DELTA", "raspberry_cover", "x-carriage", "x-end-motor", "y-belt-holder",
        "y-belt-tensioner", "y-motor-holder", "y-rod-holder")
SPLITS = {"dev": DEV, "test": TEST}
HALVES = ("dev", "test", "all")


class SplitError(SystemExit):
    """The CAD folder does not hold the parts the split names."""


def length(mesh: trimesh.Trimesh) -> float:
    """The longest side of the mesh's oriented bounding box (its unit)."""
    return float(np.max(mesh.bounding_box_oriented.primitive.extents))


def size_bin(mesh: trimesh.Trimesh) -> str:
    return next(name for name, upper in SIZES if length(mesh) < upper)


def checked_split(meshes: dict[str, trimesh.Trimesh], folder: Path,
                  min_length: float = MIN_LENGTH) -> tuple[dict, list[str]]:
    """(name -> mesh of the parts at least ``min_length`` (m) long, the names left out for being shorter),
    after checking that a folder holding most of the fixed split's parts holds exactly them."""
    kept = {n: m for n, m in meshes.items() if length(m) >= min_length}
    if not kept:
        raise SplitError(f"{folder}: no part is at least {min_length * 1e3:g} mm long (the benchmark's smallest "
                         f"part); check --units, or lower --min-length")
    if is_prusa(kept):
        listed = set(DEV) | set(TEST)
        missing, unlisted = sorted(listed - set(kept)), sorted(set(kept) - listed)
        if missing or unlisted:
            raise SplitError(f"{folder}: the split in benchmarks/generalization_parts.py does not match the "
                             f"folder's parts of at least {min_length * 1e3:g} mm (missing: {missing}, not in "
                             f"the split: {unlisted}); give the Prusa i3 folder with --cad, or update DEV and TEST")
    return kept, sorted(set(meshes) - set(kept))


def is_prusa(names) -> bool:
    """Whether parts of these names are the Prusa i3 folder the fixed split was made for: more than half of
    its parts are among them (a user's folder may share a name or two, not the set)."""
    return len(set(names) & (set(DEV) | set(TEST))) * 2 > len(DEV) + len(TEST)


def folder_split(names) -> dict[str, tuple[str, ...]]:
    """half -> part names: the fixed split for the Prusa i3 parts; for any other folder its parts, ordered by
    the SHA-256 of their names, dealt out in turn to dev and test (dev takes the odd one). ``all`` is every
    part."""
    names = sorted(names)
    if is_prusa(names):
        return {**SPLITS, "all": tuple(names)}
    dealt = sorted(names, key=lambda n: hashlib.sha256(n.encode()).hexdigest())
    return {"dev": tuple(sorted(dealt[0::2])), "test": tuple(sorted(dealt[1::2])), "all": tuple(names)}


@dataclass(frozen=True, eq=False)
class PartInfo:
    """What grading and reporting need of one part (metres)."""

    name: str
    mesh: trimesh.Trimesh
    symmetry: MeshSymmetry
    shape: PartShape
    samples: np.ndarray
    diameter: float
    size: str


def part_info(name: str, mesh: trimesh.Trimesh) -> PartInfo:
    symmetry = find_symmetries(mesh)
    samples = np.asarray(trimesh.sample.sample_surface(mesh, ADD_SAMPLES, seed=0)[0])
    return PartInfo(name, mesh, symmetry, part_shape(mesh, symmetry), samples, model_diameter(mesh), size_bin(mesh))


def class_row(info: PartInfo) -> dict:
    """The part's row of the class table (JSON)."""
    s = info.shape
    return {"part": info.name, "class": str(s.part_class), "size": info.size,
            "length_mm": round(length(info.mesh) * 1e3, 1), "resting_height_mm": round(s.resting_height * 1e3, 1),
            "primitive_share": round(s.primitive_share, 2), "revolution_share": round(s.revolution_share, 2),
            "side_share": round(s.side_share, 2), "symmetries": len(info.symmetry.turns),
            "continuous_axis": s.continuous_axis, "flanged": s.flanged}


def nearest_add(scene: MeshScene, detections, infos: dict[str, PartInfo]) -> list[float | None]:
    """Per instance, the least symmetry-aware ADD (metres) of a detection of its model, or None if none:
    how far off a part was found, when it was not found within the bar."""
    out = []
    for inst in scene.instances:
        info = infos[inst.name]
        adds = [mesh_symmetric_add(info.samples, d.T_cloud_model, inst.T_camera_model, info.symmetry)
                for d in detections if d.model == inst.name]
        out.append(min(adds) if adds else None)
    return out


def grade(scene: MeshScene, detections, infos: dict[str, PartInfo]) -> tuple[list[bool], list[bool]]:
    """(found per instance, correct per detection): a detection finds the first instance of its model not
    yet found within a symmetry-aware ADD of ADD_SHARE x the model's diameter; any other detection is
    false, a second report of an instance and a detection of a model not in the scene included."""
    return grade_instances(scene.instances, detections, infos)


def left_open(scene: MeshScene, detections, found: list[bool], correct: list[bool],
              infos: dict[str, PartInfo]) -> int:
    """How many of the false ``detections`` name, among their ``alternatives`` (the near-symmetric poses the view
    left open) or their ``rivals`` (other models' poses it left open), a pose that finds an instance no
    detection found: a tie the recognizer reported as one."""
    missed = [inst for inst, hit in zip(scene.instances, found) if not hit]
    false = [det for det, ok in zip(detections, correct) if not ok]
    return sum(any(any(grade_instances(missed, [replace(det, model=model, T_cloud_model=T, alternatives=(),
                                                        rivals=())], infos)[0])
                   for model, T in _left_open_poses(det)) for det in false)


def _left_open_poses(detection) -> list[tuple[str, np.ndarray]]:
    """The (model, pose) answers a detection reports the view could not rule out: its alternatives, its rivals,
    and its pose turned about an unfixed axis (in steps of UNFIXED_STEP_DEG)."""
    turned = []
    if detection.unfixed_turn is not None:
        point, direction = detection.unfixed_turn.point, detection.unfixed_turn.direction
        for degrees in np.arange(UNFIXED_STEP_DEG, 360.0, UNFIXED_STEP_DEG):
            turned.append((detection.model, detection.T_cloud_model @ turn_about_line(direction, np.radians(degrees),
                                                                                       point)))
    return ([(detection.model, T) for T in detection.alternatives]
            + [(r.model, r.T_cloud_model) for r in detection.rivals] + turned)


def grade_instances(instances, detections, infos: dict[str, PartInfo]) -> tuple[list[bool], list[bool]]:
    """:func:`grade` over the given ``instances`` of a scene."""
    def known(name: str):
        info = infos.get(name)
        return None if info is None else (info.samples, info.symmetry, info.diameter)
    return match_detections(instances, detections, known, ADD_SHARE)


def scene_plan(seed: int, shown: list[str], singles: int, clutter: int,
               occluded: int) -> list[tuple[SceneKind, list | None, list[int]]]:
    """(kind, the parts to show or None to draw them, seed) of every scene: ``singles`` of each part of ``shown``
    alone (seeded by its place in ``shown``), then the clutter and occluded scenes, all seeded under ``seed``."""
    plan = [(SceneKind.SINGLE, [n], [seed, 0, k, s]) for k, n in enumerate(shown) for s in range(singles)]
    plan += [(SceneKind.CLUTTER, None, [seed, 1, k]) for k in range(clutter)]
    return plan + [(SceneKind.OCCLUDED, None, [seed, 2, k]) for k in range(occluded)]
