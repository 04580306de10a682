"""The clouds Table 1 runs on (benchmarks/table1.py, whose docstring describes the cases): the seeded
full and partial views of one posed part, and their thinning to about a quarter of the points."""

from __future__ import annotations

import logging

import numpy as np
import trimesh
from scipy.spatial import Delaunay

from psorr.sensing.camera import look_at
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import PointCloud

FULL_SPACING = 0.0015        # m: full-view sampling, about a Kinect v1 pixel at 0.7-0.8 m
FULL_NOISE = 0.001           # m: Gaussian sigma of the full-view points
TABLE_PATCH = 0.4            # m: side of the table-top patch around the part in the full view


def _camera_and_pose(rng: np.random.Generator):
    """A part pose on the table (random yaw and place) and a camera as in psorr.synthetic.workpiece_scenes:
    0.65-0.8 m above the table, 20-30 deg from the vertical. Returns (T_world_model, T_world_camera)."""
    x, y, yaw = rng.uniform(-0.1, 0.1), rng.uniform(0.0, 0.2), rng.uniform(0, 2 * np.pi)
    T_world_model = trimesh.transformations.rotation_matrix(yaw, (0, 0, 1))
    T_world_model[:3, 3] = (x, y, 0.0)
    height, tilt = rng.uniform(0.65, 0.8), np.radians(rng.uniform(20.0, 30.0))
    target = np.array([0.0, 0.12, 0.0])
    return T_world_model, look_at(target + (0.0, -height * np.tan(tilt), height), target)


def _even_surface(mesh: trimesh.Trimesh, spacing: float, seed: int) -> np.ndarray:
    """About one point per spacing^2 of surface: random samples thinned so that no two
    are closer than 0.6 spacing (trimesh's rejection sampling keeps about a third of
    its draws at that radius, hence the draw count)."""
    count = int(3 * mesh.area / spacing**2)
    logger = logging.getLogger("trimesh.sample")
    level = logger.level
    logger.setLevel("ERROR")  # it warns whenever it keeps fewer than it drew, which is by design here
    try:
        points, _ = trimesh.sample.sample_surface_even(mesh, count, radius=0.6 * spacing, seed=seed)
    finally:
        logger.setLevel(level)
    return np.asarray(points)


def full_view(rng: np.random.Generator, mesh: trimesh.Trimesh):
    """(unorganised PointCloud in the camera frame, labels 0 table / 1 part, T_camera_model)."""
    T_world_model, T_world_camera = _camera_and_pose(rng)
    model_pts = _even_surface(mesh, FULL_SPACING, int(rng.integers(2**31)))
    world_model = model_pts @ T_world_model[:3, :3].T + T_world_model[:3, 3]
    # Table top: a jittered grid at the same spacing, minus the part's footprint (the part stands on it).
    half, n = TABLE_PATCH / 2, int(TABLE_PATCH / FULL_SPACING)
    gx, gy = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    table = np.column_stack([gx.ravel(), gy.ravel()]) * FULL_SPACING - half
    table += rng.uniform(0, FULL_SPACING, table.shape) + T_world_model[:2, 3]
    footprint = Delaunay(world_model[:, :2])
    table = table[footprint.find_simplex(table) < 0]
    world = np.vstack([world_model, np.column_stack([table, np.zeros(len(table))])])
    labels = np.concatenate([np.ones(len(world_model), np.int64), np.zeros(len(table), np.int64)])
    world += rng.normal(0.0, FULL_NOISE, world.shape)
    T_camera_world = np.linalg.inv(T_world_camera)
    points = world @ T_camera_world[:3, :3].T + T_camera_world[:3, 3]
    return PointCloud(points, labels=labels), T_camera_world @ T_world_model


def partial_view(rng: np.random.Generator, meshes: dict, name: str):
    """(organised Kinect-v1 PointCloud, T_camera_model) from psorr.synthetic.workpiece_scenes."""
    scene = workpiece_scene(rng, meshes, [name])
    return scene.cloud, scene.instances[0].T_camera_model


def _one_per_voxel(points: np.ndarray, voxel: float) -> np.ndarray:
    keys = np.floor(points / voxel).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    return np.sort(first)


def thin_voxel(cloud: PointCloud, spacing: float, fraction: float = 0.25) -> tuple[PointCloud, float]:
    """One point (the first) per voxel of an unorganised cloud, the voxel sized (by bisection) to
    keep about `fraction` of the points. A tilted surface cuts (|nx|+|ny|+|nz|) voxels per voxel
    face area, so a voxel of exactly 2x the spacing keeps ~40%, not 25%. Returns (cloud, voxel)."""
    pts = cloud.points[cloud.valid_mask]
    lo, hi = spacing, 5 * spacing
    for _ in range(14):
        voxel = (lo + hi) / 2
        keep = _one_per_voxel(pts, voxel)
        if abs(len(keep) / len(pts) - fraction) < 0.005:
            break
        lo, hi = (voxel, hi) if len(keep) / len(pts) > fraction else (lo, voxel)
    labels = None if cloud.labels is None else cloud.labels[cloud.valid_mask][keep]
    return PointCloud(pts[keep], labels=labels), voxel


def thin_organised(cloud: PointCloud) -> PointCloud:
    """Every 2nd row and column of an organised cloud."""
    h, w = cloud.height, cloud.width
    keep = (np.arange(h)[:, None] % 2 == 0) & (np.arange(w)[None, :] % 2 == 0)
    keep = keep.ravel()
    labels = None if cloud.labels is None else cloud.labels[keep]
    return PointCloud(cloud.points[keep], labels=labels, width=(w + 1) // 2, height=(h + 1) // 2)


def table1_cases(meshes: dict, objects, views, seeds):
    """Table 1's clouds: for each object, view ("full" or "partial") and seed, the view as is and thinned,
    as (object, view, seed, resolution ("full res" or "1/4 res"), PointCloud, T_camera_model)."""
    for name in objects:
        for view in views:
            for seed in seeds:
                rng = np.random.default_rng(seed)
                if view == "full":
                    cloud, T_true = full_view(rng, meshes[name])
                    thinned, _ = thin_voxel(cloud, FULL_SPACING)
                else:
                    cloud, T_true = partial_view(rng, meshes, name)
                    thinned = thin_organised(cloud)
                yield name, view, seed, "full res", cloud, T_true
                yield name, view, seed, "1/4 res", thinned, T_true
