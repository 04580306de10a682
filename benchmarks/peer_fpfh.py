"""Open3D's classic global registration as a peer of PSORR: table plane removed, the rest
clustered with DBSCAN; per cluster and model FPFH + feature-matching RANSAC, then point-to-plane
ICP against the full-resolution cluster; best model per cluster.

`recognize_fpfh(models, cloud, rng, params) -> list[Detection]`, with models {name: trimesh.Trimesh}
in metres in their model frames and a cloud in the sensor frame (camera at the origin, NaN rows
allowed). Tuned to do its own best on Kinect v1 clouds of 5-15 cm parts at 0.7-1 m."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
import open3d as o3d
import trimesh
from peer_common import (
    camera_normals,
    facing_camera,
    near_share,
    o3d_cloud,
    posed_points,
    remove_table,
    sample_model,
    seed,
    threads,
    valid_points,
    verify,
)
from scipy.spatial import cKDTree

from psorr.errors import InvalidInputError
from psorr.synthetic.catalog import model_diameter
from psorr.types import Detection, PointCloud

_REG = o3d.pipelines.registration


@dataclass(frozen=True)
class FpfhParams:
    """Settings of the FPFH peer; distances in metres, `*_factor`s in voxels.

    voxel: grid of the scene and the models. plane_distance: table band; points nearer the table plane are
    dropped. cluster_eps_factor, cluster_min_points: DBSCAN on the grid. merge_gap: clusters nearer than
    this merge while the union fits in max_extent_margin x the largest model diameter (a part whose base
    sinks into the table band falls apart in pieces); fewer than min_cluster_points voxels: ignored.
    model_samples: uniform surface samples per model. normal_knn: neighbours for scene normals.
    feature_*: FPFH support. ransac_*: Open3D's feature-matching RANSAC, run ransac_runs times per model
    and cluster. icp_distances_factor: the point-to-plane ICP stages. fitness_factor: a cluster point
    is explained when a posed model sample is this near. Acceptance: fitness >= min_fitness and ICP
    inlier RMSE <= max_rmse (m). threads: Open3D threads during the call (1 repeats a seed exactly).
    """

    voxel: float = 0.005
    plane_distance: float = 0.006
    plane_iterations: int = 1000
    cluster_eps_factor: float = 2.5
    cluster_min_points: int = 8
    min_cluster_points: int = 30
    merge_gap: float = 0.05
    max_extent_margin: float = 1.1
    model_samples: int = 3000
    normal_knn: int = 20
    feature_radius_factor: float = 5.0
    feature_max_nn: int = 100
    ransac_distance_factor: float = 1.5
    ransac_edge_length: float = 0.9
    ransac_mutual_filter: bool = True
    ransac_iterations: int = 100_000
    ransac_confidence: float = 0.999
    ransac_runs: int = 5
    icp_distances_factor: tuple[float, ...] = (2.0, 1.0)
    icp_iterations: int = 30
    fitness_factor: float = 3.0
    min_fitness: float = 0.7
    max_rmse: float = 0.004
    threads: int | None = 1


def _fpfh(points: np.ndarray, normals: np.ndarray, p: FpfhParams):
    pcd = o3d_cloud(points, normals)
    search = o3d.geometry.KDTreeSearchParamHybrid(radius=p.feature_radius_factor * p.voxel, max_nn=p.feature_max_nn)
    return pcd, _REG.compute_fpfh_feature(pcd, search)


_MODEL_CACHE: dict[tuple, dict] = {}


def _fpfh_model(mesh: trimesh.Trimesh, p: FpfhParams) -> dict:
    """Samples, their voxel grid (normals taken from the nearest sample) and its FPFH, made once per
    mesh and settings: the model side is the offline step, as PSORR's training and OpenCV's are.
    The samples are a fixed function of the mesh (seed 0), not of the caller's rng."""
    key = (hashlib.sha1(mesh.vertices.tobytes() + mesh.faces.tobytes()).hexdigest(), p)
    if key not in _MODEL_CACHE:
        _MODEL_CACHE[key] = _describe_model(mesh, p)
    return _MODEL_CACHE[key]


def _describe_model(mesh: trimesh.Trimesh, p: FpfhParams) -> dict:
    points, normals = sample_model(mesh, p.model_samples, np.random.default_rng(0))
    down = np.asarray(o3d_cloud(points).voxel_down_sample(p.voxel).points)
    _, nearest = cKDTree(points).query(down)
    pcd, feature = _fpfh(down, normals[nearest], p)
    return {"points": points, "normals": normals, "pcd": pcd, "feature": feature}


def _merge_near(groups: list[np.ndarray], gap: float, max_extent: float) -> list[np.ndarray]:
    """Merge point sets (M_i, 3) closer than `gap` metres while the union still fits in `max_extent`
    (the largest model's diameter): a part whose base sinks into the table band falls apart in pieces."""
    groups = list(groups)
    while len(groups) > 1:
        trees = [cKDTree(g) for g in groups]
        pairs = sorted((trees[i].query(groups[j], distance_upper_bound=gap)[0].min(), i, j)
                       for i in range(len(groups)) for j in range(i + 1, len(groups)))
        for d, i, j in pairs:
            if d <= gap and model_diameter(np.vstack((groups[i], groups[j]))) <= max_extent:
                groups[i] = np.vstack((groups[i], groups.pop(j)))
                break
        else:
            break
    return groups


def _fpfh_clusters(points: np.ndarray, p: FpfhParams, max_extent: float) -> list[np.ndarray]:
    """Full-resolution (M, 3) point sets of the object candidates standing on the table."""
    above, down = remove_table(points, p.voxel, p.plane_distance, p.plane_iterations)
    if len(down) < p.min_cluster_points:
        return []
    labels = np.asarray(o3d_cloud(down).cluster_dbscan(p.cluster_eps_factor * p.voxel, p.cluster_min_points))
    groups = _merge_near([down[labels == k] for k in range(labels.max() + 1)], p.merge_gap, max_extent)
    groups = [g for g in groups if len(g) >= p.min_cluster_points]
    if not groups:
        return []
    owner = np.concatenate([np.full(len(g), k) for k, g in enumerate(groups)])
    dist, nearest = cKDTree(np.vstack(groups)).query(above, distance_upper_bound=p.voxel)
    above_owner = np.where(np.isfinite(dist), owner[np.minimum(nearest, len(owner) - 1)], -1)
    return [above[above_owner == k] for k in range(len(groups))]


def _fpfh_hypothesis(model: dict, target: dict, p: FpfhParams) -> tuple[np.ndarray, float]:
    """One RANSAC + ICP run: pose (4, 4) model -> cloud and its last ICP inlier RMSE (m; inf if none)."""
    dist = p.ransac_distance_factor * p.voxel
    checkers = [_REG.CorrespondenceCheckerBasedOnEdgeLength(p.ransac_edge_length),
                _REG.CorrespondenceCheckerBasedOnDistance(dist)]
    result = _REG.registration_ransac_based_on_feature_matching(
        model["pcd"], target["pcd"], model["feature"], target["feature"], p.ransac_mutual_filter, dist,
        _REG.TransformationEstimationPointToPoint(False), 3, checkers,
        _REG.RANSACConvergenceCriteria(p.ransac_iterations, p.ransac_confidence))
    T, rmse = np.asarray(result.transformation), np.inf
    for factor in p.icp_distances_factor:
        facing = facing_camera(T, model["points"], model["normals"])
        if facing.sum() < 3:
            return T, np.inf
        icp = _REG.registration_icp(
            o3d_cloud(model["points"][facing]), target["full"], factor * p.voxel, T,
            _REG.TransformationEstimationPointToPlane(), _REG.ICPConvergenceCriteria(max_iteration=p.icp_iterations))
        T, rmse = np.asarray(icp.transformation), icp.inlier_rmse if icp.fitness > 0 else np.inf
    return T, rmse


def _fpfh_candidates(cache: dict, cluster: np.ndarray, rng: np.random.Generator, p: FpfhParams) -> list[tuple]:
    """(name, T (4, 4), fitness, seen, rmse, quality) of every model's best hypothesis on one cluster (M, 3).

    Each model gets ransac_runs RANSAC + ICP runs; the kept one has the best quality, the mean of the
    two-sided agreement (cluster explained, visible model samples matched; see verify) at the tightest
    ICP distance. fitness: the share of the cluster within fitness_factor voxels of the posed model.
    """
    normals = camera_normals(cluster, p.normal_knn)
    down = o3d_cloud(cluster, normals).voxel_down_sample(p.voxel)
    down.normalize_normals()
    target = {"full": o3d_cloud(cluster, normals)}
    target["pcd"], target["feature"] = _fpfh(np.asarray(down.points), np.asarray(down.normals), p)
    tree, tight, out = cKDTree(cluster), min(p.icp_distances_factor) * p.voxel, []
    for name, model in cache.items():
        best = None
        for _ in range(p.ransac_runs):
            seed(rng)
            T, rmse = _fpfh_hypothesis(model, target, p)
            explained, support, _ = verify(T, model["points"], model["normals"], cluster, tree, tight)
            quality = 0.5 * (explained + support) if np.isfinite(rmse) else 0.0
            if best is None or quality > best[1]:
                best = (T, quality, rmse)
        T, quality, rmse = best
        radius = p.fitness_factor * p.voxel
        fitness = near_share(posed_points(T, model["points"]), cluster, radius)
        seen = verify(T, model["points"], model["normals"], cluster, tree, radius)[2]
        out.append((name, T, fitness, seen, rmse, quality))
    return out


def recognize_fpfh(models: dict[str, trimesh.Trimesh], cloud: PointCloud, rng: np.random.Generator,
                   params: FpfhParams | None = None) -> list[Detection]:
    """Open3D FPFH + RANSAC + point-to-plane ICP, one Detection per accepted table-top cluster.

    Args:
        models: name -> mesh (metres, model frame).
        cloud: N points (metres, camera frame, camera at the origin); NaN rows are ignored.
        rng: the only source of randomness (Open3D's seeds); model samples are seeded by the mesh.
    Returns:
        Detections sorted by score: T_cloud_model (4, 4); score = share of the cluster's points
        within fitness_factor voxels of the posed model; visible_fraction = share of the model
        samples matched by a cluster point at that distance.
    """
    p = params or FpfhParams()
    if not models:
        raise InvalidInputError("models is empty; give at least one name -> trimesh.Trimesh")
    points = valid_points(cloud)
    max_extent = p.max_extent_margin * max(model_diameter(m) for m in models.values())
    detections = []
    with threads(p.threads), o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        seed(rng)
        clusters = _fpfh_clusters(points, p, max_extent)
        cache = {name: _fpfh_model(mesh, p) for name, mesh in sorted(models.items())}
        for cluster in clusters:
            name, T, fitness, seen, rmse, _ = max(_fpfh_candidates(cache, cluster, rng, p), key=lambda c: c[5])
            if fitness >= p.min_fitness and rmse <= p.max_rmse:
                detections.append(Detection(name, T, fitness, seen))
    return sorted(detections, key=lambda d: -d.score)


# ---------------------------------------------------------------- OpenCV PPF (Drost et al.) + ICP
