"""Seeded table-top scenes of any meshes, each part in one of its stable resting poses, ray cast from a Kinect v1.

Where :mod:`~psorr.synthetic.workpiece_scenes` stands the catalog's parts upright, these scenes take a
folder of the user's own meshes (:func:`load_meshes`, in their units) and drop each part into one of
the poses it comes to rest in (:func:`~psorr.synthetic.resting.stable_rests`, drawn by probability),
turned about the vertical and laid out without overlap. Three kinds (:class:`SceneKind`): a single
part; clutter, several parts and distractors (objects not in the library); occluded, clutter with
an arm-sized capsule across the view. The camera looks at the layout from 0.6-1.0 m, tilted 0-45
degrees from the vertical, from any side.

The cloud's labels give, per pixel, 0 for the table, k + 1 for the k-th instance, DISTRACTOR_LABEL + j
for the j-th distractor, OCCLUDER_LABEL for the capsule and -1 where there is no return. Each instance
comes with its true pose and how much of it is seen (:class:`MeshScene`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path

import numpy as np
import trimesh

from psorr.errors import CloudFileError, InvalidInputError
from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, look_at
from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise, kinect_noise_with_source
from psorr.sensing.raycast import render_meshes
from psorr.synthetic.resting import draw_rest, place_footprints, stable_rests
from psorr.synthetic.scene_visibility import instance_visibility
from psorr.synthetic.workpiece_scenes import (
    OCCLUDER_LABEL,
    TABLE_LABEL,
    PlacedWorkpiece,
    WorkpieceScene,
    _occluding_capsule,
)

DISTRACTOR_LABEL = 2000
PATCH_CENTRE = np.array([0.0, 0.12, 0.0])  # where workpiece_scene's occluding capsule crosses the table


class SceneKind(StrEnum):
    SINGLE = "single"
    CLUTTER = "clutter"
    OCCLUDED = "occluded"


@dataclass(frozen=True)
class SceneParams:
    """How :func:`mesh_scene` draws a scene; metres and degrees.

    Attributes:
        camera_distance: (min, max) distance from the camera to the table point it looks at.
        camera_tilt_deg: (min, max) angle of the line of sight from the vertical.
        clutter_parts: (min, max) library parts in a clutter or occluded scene.
        distractors: (min, max) distractors in a clutter or occluded scene.
        patch_half_extents: the layout's half sizes on the table: every part lies inside it (it stays in
            view at 0.6 m from any side and up to 45 degrees).
        gap: the least distance between two objects' outlines on the table.
        table_extents: the table box, centred under the layout.
        intrinsics: the camera. noise: the sensor noise (None for clean depth).
        visibility_samples: model surface samples per instance for its visibility.
    """

    camera_distance: tuple[float, float] = (0.6, 1.0)
    camera_tilt_deg: tuple[float, float] = (0.0, 45.0)
    clutter_parts: tuple[int, int] = (3, 5)
    distractors: tuple[int, int] = (1, 3)
    patch_half_extents: tuple[float, float] = (0.18, 0.18)
    gap: float = 0.01
    table_extents: tuple[float, float, float] = (2.0, 2.0, 0.03)
    intrinsics: CameraIntrinsics = field(default_factory=CameraIntrinsics)
    noise: KinectNoise | None = KINECT_V1
    visibility_samples: int = 2000

    def __post_init__(self):
        for name in ("camera_distance", "camera_tilt_deg", "clutter_parts", "distractors"):
            low, high = getattr(self, name)
            if not 0 <= low <= high:
                raise InvalidInputError(f"SceneParams.{name} must be (min, max), 0 <= min <= max; got {(low, high)}")
        if self.camera_tilt_deg[1] >= 90 or self.camera_distance[0] <= 0 or self.clutter_parts[0] < 1:
            raise InvalidInputError("SceneParams: the tilt must stay under 90 degrees, the distance above 0, and a "
                                    "clutter scene needs at least one part")


@dataclass(frozen=True, eq=False)
class MeshScene(WorkpieceScene):
    """A :class:`~psorr.synthetic.workpiece_scenes.WorkpieceScene` (cloud, instances with T_camera_model,
    T_world_camera, intrinsics), and:

    Attributes:
        kind: the scene's kind.
        distractors: the objects not in the library (names and poses); distractors[j] has the label
            DISTRACTOR_LABEL + j.
        visibility: per instance, the share of its surface samples that the sensor would see were it alone
            on the table which it does see past the other objects and out of their projector shadow (no
            other sensor noise): 1 unoccluded.
        seen_share: per instance, the share of all its surface samples that the sensor measured.
    """

    kind: SceneKind = SceneKind.SINGLE
    distractors: tuple[PlacedWorkpiece, ...] = ()
    visibility: tuple[float, ...] = ()
    seen_share: tuple[float, ...] = ()


def load_meshes(folder, units: str) -> dict[str, trimesh.Trimesh]:
    """Every .stl, .obj and .ply mesh in ``folder``, scaled to metres from ``units`` ('m', 'cm', 'mm' or 'in':
    psorr.io.meshes.UNITS), by file stem."""
    from psorr.io.meshes import MESH_SUFFIXES
    from psorr.library.models import load_mesh_in_metres

    folder = Path(folder)
    if not folder.is_dir():
        raise CloudFileError(folder, "no such folder", "give the folder that holds the mesh files")
    paths = sorted(p for p in folder.iterdir() if p.suffix.lower() in MESH_SUFFIXES)
    if not paths:
        raise CloudFileError(folder, f"holds no mesh files ({', '.join(MESH_SUFFIXES)})", "export the parts there")
    return {p.stem: load_mesh_in_metres(p, units) for p in paths}


def simple_shapes() -> dict[str, trimesh.Trimesh]:
    """Distractors that are nobody's part: a box, a cylinder, a ball and a cone, 40-60 mm, in metres."""
    return {"shape-box": trimesh.creation.box((0.06, 0.04, 0.03)),
            "shape-cylinder": trimesh.creation.cylinder(radius=0.02, height=0.06, sections=48),
            "shape-ball": trimesh.creation.icosphere(subdivisions=3, radius=0.025),
            "shape-cone": trimesh.creation.cone(radius=0.03, height=0.05, sections=48)}


def _draw_names(rng, parts: dict, distractors: dict, kind: SceneKind, names: list[str] | None,
                p: SceneParams) -> tuple[list, list]:
    """(parts, distractors) to show: ``names`` or drawn parts, and drawn distractors in clutter."""
    if names is None and kind is SceneKind.SINGLE:
        names = [str(rng.choice(sorted(parts)))]
    elif names is None:
        count = min(int(rng.integers(p.clutter_parts[0], p.clutter_parts[1] + 1)), len(parts))
        names = [str(n) for n in rng.choice(sorted(parts), size=count, replace=False)]
    if kind is SceneKind.SINGLE:
        return list(names), []
    others = min(int(rng.integers(p.distractors[0], p.distractors[1] + 1)), len(distractors))
    return names, [str(n) for n in rng.choice(sorted(distractors), size=others, replace=False)]


def _camera(rng, p: SceneParams) -> np.ndarray:
    """T_world_camera looking at the layout's centre from a drawn distance, tilt and side."""
    distance = rng.uniform(*p.camera_distance)
    tilt, side = np.radians(rng.uniform(*p.camera_tilt_deg)), rng.uniform(0.0, 2 * np.pi)
    towards = np.array([np.cos(side), np.sin(side), 0.0])
    eye = PATCH_CENTRE + distance * (np.sin(tilt) * towards + (0.0, 0.0, np.cos(tilt)))
    return look_at(eye, PATCH_CENTRE, up=-towards)  # image up is away from the camera, even looking straight down


def _layout(rng, meshes: list[trimesh.Trimesh], p: SceneParams) -> list[np.ndarray]:
    """T_world_model of each mesh: a drawn stable rest, turned and placed in the patch without overlap."""
    rests = [draw_rest(rng, stable_rests(m)) for m in meshes]
    places = place_footprints(rng, [r.footprint for r in rests], p.patch_half_extents, p.gap)
    poses = []
    for rest, (x, y, yaw) in zip(rests, places):
        T = trimesh.transformations.rotation_matrix(yaw, (0, 0, 1))
        T[:3, 3] = PATCH_CENTRE + (x, y, 0.0)
        poses.append(T @ rest.T_table_model)
    return poses


def _check(parts: dict, distractors: dict, names: list[str] | None) -> None:
    if not parts:
        raise InvalidInputError("parts is empty; give name -> trimesh.Trimesh (metres), e.g. load_meshes(folder, 'mm')")
    shared = sorted(set(parts) & set(distractors))
    if shared:
        raise InvalidInputError(f"{shared} are both parts and distractors; a distractor must not be a library part")
    unknown = sorted(set(names or ()) - set(parts))
    if unknown:
        raise InvalidInputError(f"unknown parts {unknown}; choose from {sorted(parts)}")


def mesh_scene(rng: np.random.Generator, parts: dict[str, trimesh.Trimesh], kind: SceneKind | str = SceneKind.SINGLE,
               names: list[str] | None = None, distractors: dict[str, trimesh.Trimesh] | None = None,
               params: SceneParams | None = None) -> MeshScene:
    """Render library parts (and, in clutter, distractors) resting on a table.

    Args:
        rng: draws, in order: the parts (unless ``names`` are given) and distractors, each object's rest,
            the layout, the camera, the occluder (occluded scenes), then the sensor noise.
        parts: name -> mesh (metres, model frame): the library's parts.
        kind: single, clutter or occluded (a SceneKind or its value).
        names: the parts to show, each once; None to draw one (single) or clutter_parts of them.
        distractors: name -> mesh (metres) of objects not in the library, drawn from in clutter;
            None for :func:`simple_shapes`.
        params: the scene's settings; None for the defaults.
    """
    if kind not in tuple(SceneKind):
        raise InvalidInputError(f"unknown scene kind {kind!r}; choose one of {[k.value for k in SceneKind]}")
    kind, p = SceneKind(kind), params or SceneParams()
    distractors = simple_shapes() if distractors is None else distractors
    _check(parts, distractors, names)
    names, others = _draw_names(rng, parts, distractors, kind, names, p)
    meshes = [parts[n] for n in names] + [distractors[n] for n in others]
    poses = _layout(rng, meshes, p)
    table = trimesh.creation.box(extents=p.table_extents)
    table.apply_translation(PATCH_CENTRE - (0.0, 0.0, p.table_extents[2] / 2))
    labels = [k + 1 for k in range(len(names))] + [DISTRACTOR_LABEL + j for j in range(len(others))]
    world = [(table, TABLE_LABEL)] + [(m.copy().apply_transform(T), lab) for m, T, lab in zip(meshes, poses, labels)]
    T_world_camera = _camera(rng, p)
    if kind is SceneKind.OCCLUDED:
        world.append((_occluding_capsule(rng), OCCLUDER_LABEL))
    clean_depth, clean_ids = render_meshes(world, T_world_camera, p.intrinsics)
    depth, ids = clean_depth, clean_ids
    if p.noise is not None:
        depth, source = kinect_noise_with_source(clean_depth, p.intrinsics, rng, p.noise)
        ids = np.where(depth > 0, clean_ids.ravel()[source], -1)
    T_camera_world = np.linalg.inv(T_world_camera)
    placed = [PlacedWorkpiece(n, T_camera_world @ T) for n, T in zip(names + others, poses)]
    baseline = p.noise.baseline if p.noise is not None and p.noise.shadow else None
    views = [instance_visibility(parts[inst.name], inst.T_camera_model, k + 1, clean_depth, clean_ids, ids,
                                 p.intrinsics, p.visibility_samples, baseline)
             for k, inst in enumerate(placed[:len(names)])]
    return MeshScene(depth_to_cloud(depth, p.intrinsics, labels=ids), tuple(placed[:len(names)]), T_world_camera,
                     p.intrinsics, kind, tuple(placed[len(names):]), tuple(v[0] for v in views),
                     tuple(v[1] for v in views))
