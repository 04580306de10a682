"""Steps the benchmark's peer methods share: seeding and thread limits, table removal, visibility
and the point check that accepts a peer's pose (:mod:`peer_fpfh`, :mod:`peer_opencv`)."""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np
import open3d as o3d
import trimesh
from scipy.spatial import cKDTree

from psorr.errors import InvalidInputError
from psorr.geometry.open3d_threads import limited_threads
from psorr.synthetic.catalog import symmetric_add
from psorr.types import PointCloud

# ---------------------------------------------------------------- shared steps


def seed(rng: np.random.Generator):
    """Seed Open3D's global generator from rng."""
    o3d.utility.random.seed(int(rng.integers(0, 2**31 - 1)))


@contextmanager
def threads(n: int | None, cv2=None):
    """Run Open3D (and OpenCV, when given its module) on at most n threads inside the block (None: leave
    them be). Their RANSAC and voting draw and gather across threads, so only n = 1 repeats a seed exactly."""
    if n is None:
        yield
        return
    before = cv2.getNumThreads() if cv2 else None
    if cv2:
        cv2.setNumThreads(n)
    try:
        with limited_threads(n):
            yield
    finally:
        if cv2:
            cv2.setNumThreads(before)


def o3d_cloud(points: np.ndarray, normals: np.ndarray | None = None) -> o3d.geometry.PointCloud:
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.ascontiguousarray(points, dtype=np.float64)))
    if normals is not None:
        pcd.normals = o3d.utility.Vector3dVector(np.ascontiguousarray(normals, dtype=np.float64))
    return pcd


def camera_normals(points: np.ndarray, knn: int) -> np.ndarray:
    """(N, 3) unit normals from the k nearest neighbours, turned towards the camera at the origin."""
    pcd = o3d_cloud(points)
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn))
    normals = np.asarray(pcd.normals)
    normals[np.einsum("ij,ij->i", normals, points) > 0] *= -1
    return normals


def sample_model(mesh: trimesh.Trimesh, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(count, 3) points and (count, 3) outward normals drawn uniformly over the mesh surface."""
    points, faces = trimesh.sample.sample_surface(mesh, count, seed=rng)
    return np.asarray(points, np.float64), np.asarray(mesh.face_normals[faces], np.float64)


def remove_table(points: np.ndarray, voxel: float, distance: float, iterations: int):
    """Find the dominant plane on a `voxel` grid of points (N, 3) and keep what stands above it.

    Returns (above (M, 3) full-resolution points more than `distance` metres on the camera
    side of the plane, down (K, 3) the voxel-grid points likewise above it).
    """
    down = o3d_cloud(points).voxel_down_sample(voxel)
    if len(down.points) < 3:
        raise InvalidInputError("the cloud has fewer than 3 valid points after downsampling")
    plane, _ = down.segment_plane(distance_threshold=distance, ransac_n=3, num_iterations=iterations)
    plane = np.asarray(plane, np.float64) / np.linalg.norm(plane[:3])
    plane *= np.sign(plane[3]) or 1.0  # normal towards the camera at the origin: n.0 + d > 0
    down_pts = np.asarray(down.points)
    return (points[points @ plane[:3] + plane[3] > distance], down_pts[down_pts @ plane[:3] + plane[3] > distance])


def valid_points(cloud: PointCloud) -> np.ndarray:
    if not isinstance(cloud, PointCloud):
        raise InvalidInputError(f"cloud must be a psorr PointCloud, got {type(cloud).__name__}")
    points = cloud.points[cloud.valid_mask]
    if len(points) < 3:
        raise InvalidInputError("the cloud has fewer than 3 valid (non-NaN) points")
    return points


def posed_points(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ T[:3, :3].T + T[:3, 3]


def facing_camera(T: np.ndarray, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(N,) bool: model samples whose normal, under pose T, faces the camera at the origin."""
    return np.einsum("ij,ij->i", normals @ T[:3, :3].T, posed_points(T, points)) < 0


def visible_samples(T: np.ndarray, points: np.ndarray, normals: np.ndarray, cell: float) -> np.ndarray:
    """(N,) bool: model samples (N, 3) with normals (N, 3) that, posed by T (4, 4), face the camera and are
    not hidden behind other samples: a z-buffer over viewing directions binned `cell` metres wide at 1 m."""
    posed, facing = posed_points(T, points), facing_camera(T, points, normals)
    z = posed[:, 2]
    if not (z > 0).all():
        return facing & (z > 0)
    bins = np.floor(posed[:, :2] / (z[:, None] * cell)).astype(np.int64)
    _, inverse = np.unique(bins, axis=0, return_inverse=True)
    nearest = np.full(inverse.max() + 1, np.inf)
    np.minimum.at(nearest, inverse, z)
    return facing & (z <= nearest[inverse] + cell * z)


def near_share(points: np.ndarray, queries: np.ndarray, radius: float) -> float:
    """Share of the queries (K, 3) within radius (metres) of a point of points (N, 3); 0 when K = 0."""
    return float(np.mean(cKDTree(points).query(queries, distance_upper_bound=radius)[0] < radius)) if len(
        queries) else 0.0


def verify(T: np.ndarray, points: np.ndarray, normals: np.ndarray, scene: np.ndarray, tree: cKDTree,
            radius: float) -> tuple[float, float, float]:
    """Agreement of a posed model (samples (N, 3), normals (N, 3), pose T (4, 4)) with scene points (M, 3).

    Returns (explained: share of the scene points within the posed model's bounding sphere that lie within
    radius of a model sample; support: share of the model samples the camera would see that have a scene
    point within radius; seen: that share over all samples)."""
    posed = posed_points(T, points)
    centre = posed.mean(axis=0)
    local = scene[tree.query_ball_point(centre, np.linalg.norm(posed - centre, axis=1).max())]
    explained = near_share(posed, local, radius)
    hit = tree.query(posed, distance_upper_bound=radius)[0] < radius
    visible = visible_samples(T, points, normals, 2.0 * radius / max(float(np.median(posed[:, 2])), 1e-3))
    return explained, float(hit[visible].mean()) if visible.any() else 0.0, float(hit.mean())


def grade(scene, detections, catalog, samples, diameters) -> tuple[int, int]:
    """(instances found, false detections) of ``detections`` in a synthetic ``scene``: a detection finds an
    instance of its model not found yet within a symmetry-aware ADD of 0.1 x the model's diameter
    (``samples`` and ``diameters`` per model name); one that finds none is false, a second report of
    an instance included."""
    found, false = set(), 0
    for det in detections:
        hits = [k for k, inst in enumerate(scene.instances) if k not in found and inst.name == det.model and
                symmetric_add(samples[det.model], det.T_cloud_model, inst.T_camera_model, catalog[inst.name])
                < 0.1 * diameters[det.model]]
        if hits:
            found.add(hits[0])
        else:
            false += 1
    return len(found), false


def catalog_library():
    """The catalog, its meshes (name -> trimesh), the library of all its parts (trained or cached), and per
    model name its ADD samples (every 10th surface point) and diameter (m): what grading needs."""
    from psorr.library.models import ModelLibrary
    from psorr.synthetic.catalog import load_catalog

    catalog = load_catalog()
    meshes = {name: catalog[name].load_mesh() for name in sorted(catalog)}
    library = ModelLibrary.from_meshes([catalog[n].mesh_path for n in sorted(catalog)])
    samples = {m.name: m.points[::10] for m in library.models}
    return catalog, meshes, library, samples, {m.name: m.diameter for m in library.models}


def clutter_scene(seed: int, catalog, meshes, intrinsics=None):
    """The seeded 4-part clutter scene ``seed`` with the capsule occluder (the parts drawn by seed, the
    layout, camera and noise by 1000 + seed)."""
    from psorr.synthetic.workpiece_scenes import workpiece_scene

    names = list(np.random.default_rng(seed).choice(sorted(catalog), size=4, replace=False))
    return workpiece_scene(np.random.default_rng(1000 + seed), meshes, names, intrinsics=intrinsics, occluder=True)
