"""Seeded table-top scenes of CAD workpieces, ray cast from a Kinect v1.

Each workpiece stands at identity orientation in its model frame (origin at
the centre of its resting face, +z up), turned about the vertical and placed
on the table without overlap. The cloud's labels give, per pixel, 0 for the
table, k + 1 for the k-th instance and -1 where there is no return.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from psorr.errors import InvalidInputError
from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, look_at
from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise, kinect_noise_with_source
from psorr.sensing.raycast import render_meshes
from psorr.synthetic.primitive_scenes import TABLE_EXTENTS
from psorr.types import PointCloud

TABLE_LABEL = 0
OCCLUDER_LABEL = 1000


@dataclass(frozen=True, eq=False)
class PlacedWorkpiece:
    """One instance: its model name and T_camera_model (4, 4), model -> camera frame."""

    name: str
    T_camera_model: np.ndarray


@dataclass(frozen=True, eq=False)
class WorkpieceScene:
    """cloud: organised, labels as in the module docstring. instances[k] has label k + 1."""

    cloud: PointCloud
    instances: tuple[PlacedWorkpiece, ...]
    T_world_camera: np.ndarray
    intrinsics: CameraIntrinsics


def _place(rng, footprints, n_tries: int = 200):
    """(x, y, yaw) for each footprint radius, in a 0.5 x 0.35 m patch, not overlapping."""
    placed = []
    for radius in footprints:
        for _ in range(n_tries):
            x, y = rng.uniform(-0.25, 0.25), rng.uniform(-0.05, 0.30)
            if all(np.hypot(x - px, y - py) > radius + pr + 0.01 for px, py, _, pr in placed):
                placed.append((x, y, rng.uniform(0, 2 * np.pi), radius))
                break
        else:
            raise InvalidInputError(f"could not fit {len(footprints)} workpieces on the table; use fewer")
    return placed


def _occluding_capsule(rng) -> trimesh.Trimesh:
    """An arm-sized capsule (radius 3.5 cm, 0.7 m long) 15-25 cm above the
    table, crossing the parts' patch at a random heading, as a person's arm would."""
    capsule = trimesh.creation.capsule(height=0.7, radius=0.035)
    capsule.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0)))
    T = trimesh.transformations.rotation_matrix(rng.uniform(0, np.pi), (0, 0, 1))
    T[:3, 3] = (rng.uniform(-0.1, 0.1), rng.uniform(0.05, 0.2), rng.uniform(0.15, 0.25))
    return capsule.apply_transform(T)


def workpiece_scene(rng: np.random.Generator, meshes: dict[str, trimesh.Trimesh], names: list[str],
                    noise: KinectNoise | None = KINECT_V1,
                    intrinsics: CameraIntrinsics | None = None, occluder: bool = False) -> WorkpieceScene:
    """Render the named workpieces (keys of `meshes`, model frame, metres) on a table.

    rng draws the layout, then the camera (0.65-0.8 m above the table,
    20-30 deg from the vertical), then the occluder if asked for (its pixels
    are labelled OCCLUDER_LABEL), then the sensor noise.
    """
    unknown = sorted(set(names) - set(meshes))
    if unknown:
        raise InvalidInputError(f"unknown workpieces {unknown}; choose from {sorted(meshes)}")
    intrinsics = intrinsics or CameraIntrinsics()
    footprints = [float(np.linalg.norm(meshes[n].bounds[:, :2], axis=1).max()) for n in names]
    table = trimesh.creation.box(extents=TABLE_EXTENTS)
    table.apply_translation((0.0, 0.1, -TABLE_EXTENTS[2] / 2))
    world_meshes, T_world_models = [(table, TABLE_LABEL)], []
    for k, (name, (x, y, yaw, _)) in enumerate(zip(names, _place(rng, footprints))):
        T = trimesh.transformations.rotation_matrix(yaw, (0, 0, 1))
        T[:3, 3] = (x, y, 0.0)
        T_world_models.append(T)
        world_meshes.append((meshes[name].copy().apply_transform(T), k + 1))
    height, tilt = rng.uniform(0.65, 0.8), np.radians(rng.uniform(20.0, 30.0))
    target = np.array([0.0, 0.12, 0.0])
    T_world_camera = look_at(target + (0.0, -height * np.tan(tilt), height), target)
    if occluder:
        world_meshes.append((_occluding_capsule(rng), OCCLUDER_LABEL))
    depth, ids = render_meshes(world_meshes, T_world_camera, intrinsics)
    if noise is not None:
        depth, source = kinect_noise_with_source(depth, intrinsics, rng, noise)
        ids = np.where(depth > 0, ids.ravel()[source], -1)
    T_camera_world = np.linalg.inv(T_world_camera)
    instances = tuple(PlacedWorkpiece(n, T_camera_world @ T) for n, T in zip(names, T_world_models))
    return WorkpieceScene(depth_to_cloud(depth, intrinsics, labels=ids), instances, T_world_camera, intrinsics)
