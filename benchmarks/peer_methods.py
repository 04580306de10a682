"""The two peer methods the recognition benchmark compares PSORR against.

Both take the same call, `recognize_*(models, cloud, rng, params) -> list[Detection]`, with
models {name: trimesh.Trimesh} in metres in their model frames and a cloud in the sensor
frame (camera at the origin, NaN rows allowed):

- recognize_fpfh: Open3D's classic global registration. Table plane removed, the rest
  clustered with DBSCAN; per cluster and model FPFH + feature-matching RANSAC, then
  point-to-plane ICP against the full-resolution cluster; best model per cluster.
- recognize_ppf_opencv: Drost et al.'s point pair features, OpenCV's
  cv2.ppf_match_3d.PPF3DDetector, refined by its ICP, on the scene without the table.
  Needs the optional extra: pip install opencv-contrib-python-headless.

Both are tuned to do their own best on Kinect v1 clouds of 5-15 cm parts at 0.7-1 m.
"""

from __future__ import annotations

import hashlib
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import open3d as o3d
import trimesh
from scipy.spatial import cKDTree

from psorr.errors import InvalidInputError, PsorrError
from psorr.types import Detection, PointCloud
from psorr.workpieces import model_diameter

_REG = o3d.pipelines.registration


# ---------------------------------------------------------------- shared steps


def _seed(rng: np.random.Generator):
    """Seed Open3D's global generator from rng."""
    o3d.utility.random.seed(int(rng.integers(0, 2**31 - 1)))


@contextmanager
def _threads(n: int | None, cv2=None):
    """Run Open3D (and OpenCV, when given its module) on at most n threads inside the block (None: leave
    them be). Their RANSAC and voting draw and gather across threads, so only n = 1 repeats a seed exactly."""
    if n is None:
        yield
        return
    before = o3d.utility.get_max_threads(), cv2.getNumThreads() if cv2 else None
    o3d.utility.set_max_threads(n)
    if cv2:
        cv2.setNumThreads(n)
    try:
        yield
    finally:
        o3d.utility.set_max_threads(before[0])
        if cv2:
            cv2.setNumThreads(before[1])


def _pcd(points: np.ndarray, normals: np.ndarray | None = None) -> o3d.geometry.PointCloud:
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.ascontiguousarray(points, dtype=np.float64)))
    if normals is not None:
        pcd.normals = o3d.utility.Vector3dVector(np.ascontiguousarray(normals, dtype=np.float64))
    return pcd


def _camera_normals(points: np.ndarray, knn: int) -> np.ndarray:
    """(N, 3) unit normals from the k nearest neighbours, turned towards the camera at the origin."""
    pcd = _pcd(points)
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn))
    normals = np.asarray(pcd.normals)
    normals[np.einsum("ij,ij->i", normals, points) > 0] *= -1
    return normals


def _sample_model(mesh: trimesh.Trimesh, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(count, 3) points and (count, 3) outward normals drawn uniformly over the mesh surface."""
    points, faces = trimesh.sample.sample_surface(mesh, count, seed=rng)
    return np.asarray(points, np.float64), np.asarray(mesh.face_normals[faces], np.float64)


def _remove_table(points: np.ndarray, voxel: float, distance: float, iterations: int):
    """Find the dominant plane on a `voxel` grid of points (N, 3) and keep what stands above it.

    Returns (above (M, 3) full-resolution points more than `distance` metres on the camera
    side of the plane, down (K, 3) the voxel-grid points likewise above it).
    """
    down = _pcd(points).voxel_down_sample(voxel)
    if len(down.points) < 3:
        raise InvalidInputError("the cloud has fewer than 3 valid points after downsampling")
    plane, _ = down.segment_plane(distance_threshold=distance, ransac_n=3, num_iterations=iterations)
    plane = np.asarray(plane, np.float64) / np.linalg.norm(plane[:3])
    plane *= np.sign(plane[3]) or 1.0  # normal towards the camera at the origin: n.0 + d > 0
    down_pts = np.asarray(down.points)
    return (points[points @ plane[:3] + plane[3] > distance], down_pts[down_pts @ plane[:3] + plane[3] > distance])


def _valid_points(cloud: PointCloud) -> np.ndarray:
    if not isinstance(cloud, PointCloud):
        raise InvalidInputError(f"cloud must be a psorr PointCloud, got {type(cloud).__name__}")
    points = cloud.points[cloud.valid_mask]
    if len(points) < 3:
        raise InvalidInputError("the cloud has fewer than 3 valid (non-NaN) points")
    return points


def _posed(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ T[:3, :3].T + T[:3, 3]


def _facing_camera(T: np.ndarray, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(N,) bool: model samples whose normal, under pose T, faces the camera at the origin."""
    return np.einsum("ij,ij->i", normals @ T[:3, :3].T, _posed(T, points)) < 0


def _visible(T: np.ndarray, points: np.ndarray, normals: np.ndarray, cell: float) -> np.ndarray:
    """(N,) bool: model samples (N, 3) with normals (N, 3) that, posed by T (4, 4), face the camera and are
    not hidden behind other samples: a z-buffer over viewing directions binned `cell` metres wide at 1 m."""
    posed, facing = _posed(T, points), _facing_camera(T, points, normals)
    z = posed[:, 2]
    if not (z > 0).all():
        return facing & (z > 0)
    bins = np.floor(posed[:, :2] / (z[:, None] * cell)).astype(np.int64)
    _, inverse = np.unique(bins, axis=0, return_inverse=True)
    nearest = np.full(inverse.max() + 1, np.inf)
    np.minimum.at(nearest, inverse, z)
    return facing & (z <= nearest[inverse] + cell * z)


def _near_share(points: np.ndarray, queries: np.ndarray, radius: float) -> float:
    """Share of the queries (K, 3) within radius (metres) of a point of points (N, 3); 0 when K = 0."""
    return float(np.mean(cKDTree(points).query(queries, distance_upper_bound=radius)[0] < radius)) if len(
        queries) else 0.0


def _verify(T: np.ndarray, points: np.ndarray, normals: np.ndarray, scene: np.ndarray, tree: cKDTree,
            radius: float) -> tuple[float, float, float]:
    """Agreement of a posed model (samples (N, 3), normals (N, 3), pose T (4, 4)) with scene points (M, 3).

    Returns (explained: share of the scene points within the posed model's bounding sphere that lie within
    radius of a model sample; support: share of the model samples the camera would see that have a scene
    point within radius; seen: that share over all samples)."""
    posed = _posed(T, points)
    centre = posed.mean(axis=0)
    local = scene[tree.query_ball_point(centre, np.linalg.norm(posed - centre, axis=1).max())]
    explained = _near_share(posed, local, radius)
    hit = tree.query(posed, distance_upper_bound=radius)[0] < radius
    visible = _visible(T, points, normals, 2.0 * radius / max(float(np.median(posed[:, 2])), 1e-3))
    return explained, float(hit[visible].mean()) if visible.any() else 0.0, float(hit.mean())


# ---------------------------------------------------------------- Open3D FPFH + RANSAC + ICP


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
    pcd = _pcd(points, normals)
    search = o3d.geometry.KDTreeSearchParamHybrid(radius=p.feature_radius_factor * p.voxel, max_nn=p.feature_max_nn)
    return pcd, _REG.compute_fpfh_feature(pcd, search)


def _fpfh_model(mesh: trimesh.Trimesh, rng: np.random.Generator, p: FpfhParams) -> dict:
    """Samples, their voxel grid (normals taken from the nearest sample) and its FPFH."""
    points, normals = _sample_model(mesh, p.model_samples, rng)
    down = np.asarray(_pcd(points).voxel_down_sample(p.voxel).points)
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
    above, down = _remove_table(points, p.voxel, p.plane_distance, p.plane_iterations)
    if len(down) < p.min_cluster_points:
        return []
    labels = np.asarray(_pcd(down).cluster_dbscan(p.cluster_eps_factor * p.voxel, p.cluster_min_points))
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
        facing = _facing_camera(T, model["points"], model["normals"])
        if facing.sum() < 3:
            return T, np.inf
        icp = _REG.registration_icp(
            _pcd(model["points"][facing]), target["full"], factor * p.voxel, T,
            _REG.TransformationEstimationPointToPlane(), _REG.ICPConvergenceCriteria(max_iteration=p.icp_iterations))
        T, rmse = np.asarray(icp.transformation), icp.inlier_rmse if icp.fitness > 0 else np.inf
    return T, rmse


def _fpfh_candidates(cache: dict, cluster: np.ndarray, rng: np.random.Generator, p: FpfhParams) -> list[tuple]:
    """(name, T (4, 4), fitness, seen, rmse, quality) of every model's best hypothesis on one cluster (M, 3).

    Each model gets ransac_runs RANSAC + ICP runs; the kept one has the best quality, the mean of the
    two-sided agreement (cluster explained, visible model samples matched; see _verify) at the tightest
    ICP distance. fitness: the share of the cluster within fitness_factor voxels of the posed model.
    """
    normals = _camera_normals(cluster, p.normal_knn)
    down = _pcd(cluster, normals).voxel_down_sample(p.voxel)
    down.normalize_normals()
    target = {"full": _pcd(cluster, normals)}
    target["pcd"], target["feature"] = _fpfh(np.asarray(down.points), np.asarray(down.normals), p)
    tree, tight, out = cKDTree(cluster), min(p.icp_distances_factor) * p.voxel, []
    for name, model in cache.items():
        best = None
        for _ in range(p.ransac_runs):
            _seed(rng)
            T, rmse = _fpfh_hypothesis(model, target, p)
            explained, support, _ = _verify(T, model["points"], model["normals"], cluster, tree, tight)
            quality = 0.5 * (explained + support) if np.isfinite(rmse) else 0.0
            if best is None or quality > best[1]:
                best = (T, quality, rmse)
        T, quality, rmse = best
        radius = p.fitness_factor * p.voxel
        fitness = _near_share(_posed(T, model["points"]), cluster, radius)
        seen = _verify(T, model["points"], model["normals"], cluster, tree, radius)[2]
        out.append((name, T, fitness, seen, rmse, quality))
    return out


def recognize_fpfh(models: dict[str, trimesh.Trimesh], cloud: PointCloud, rng: np.random.Generator,
                   params: FpfhParams | None = None) -> list[Detection]:
    """Open3D FPFH + RANSAC + point-to-plane ICP, one Detection per accepted table-top cluster.

    Args:
        models: name -> mesh (metres, model frame).
        cloud: N points (metres, camera frame, camera at the origin); NaN rows are ignored.
        rng: the only source of randomness (model sampling and Open3D's seeds).
    Returns:
        Detections sorted by score: T_cloud_model (4, 4); score = share of the cluster's points
        within fitness_factor voxels of the posed model; visible_fraction = share of the model
        samples matched by a cluster point at that distance.
    """
    p = params or FpfhParams()
    if not models:
        raise InvalidInputError("models is empty; give at least one name -> trimesh.Trimesh")
    points = _valid_points(cloud)
    max_extent = p.max_extent_margin * max(model_diameter(m) for m in models.values())
    detections = []
    with _threads(p.threads), o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        _seed(rng)
        clusters = _fpfh_clusters(points, p, max_extent)
        cache = {name: _fpfh_model(mesh, rng, p) for name, mesh in sorted(models.items())}
        for cluster in clusters:
            name, T, fitness, seen, rmse, _ = max(_fpfh_candidates(cache, cluster, rng, p), key=lambda c: c[5])
            if fitness >= p.min_fitness and rmse <= p.max_rmse:
                detections.append(Detection(name, T, fitness, seen))
    return sorted(detections, key=lambda d: -d.score)


# ---------------------------------------------------------------- OpenCV PPF (Drost et al.) + ICP


@dataclass(frozen=True)
class OpencvPpfParams:
    """Settings of the OpenCV PPF peer; distances in metres, `relative_*` in model diameters.

    voxel, plane_distance, plane_iterations: table removal as in FpfhParams. model_samples: surface
    samples per model handed to training. relative_sampling_step, relative_distance_step, num_angles:
    PPF3DDetector's training grid. scene_sample_step: share of the sampled scene points used as
    reference points; scene_distance: the scene's sampling step. normal_knn: neighbours for scene
    normals. top_k: hypotheses per model refined by ICP. icp_*: cv2.ppf_match_3d.ICP settings.
    support_distance: a model sample or scene point is matched when the other is this near (see _verify).
    min_votes, max_residual (OpenCV ICP's residual, in its own normalised units), min_score: acceptance.
    nms_factor: detections whose centroids are nearer than this times the smaller diameter are one object.
    threads: Open3D and OpenCV threads during the call (1 repeats a seed exactly).
    """

    voxel: float = 0.005
    plane_distance: float = 0.006
    plane_iterations: int = 1000
    model_samples: int = 1000
    relative_sampling_step: float = 0.05
    relative_distance_step: float = 0.05
    num_angles: int = 30
    scene_sample_step: float = 1.0 / 3.0
    scene_distance: float = 0.03
    normal_knn: int = 20
    top_k: int = 5
    icp_iterations: int = 100
    icp_tolerance: float = 0.005
    icp_rejection_scale: float = 2.5
    icp_levels: int = 4
    icp_crop: float = 0.75
    support_distance: float = 0.006
    min_votes: int = 10
    max_residual: float = 0.04
    min_score: float = 0.6
    nms_factor: float = 0.5
    threads: int | None = 1


_PPF_CACHE: dict[tuple, tuple] = {}


def _cv2():
    try:
        import cv2
    except ImportError as exc:
        raise PsorrError("the OpenCV PPF peer needs OpenCV's contrib modules: "
                         "pip install opencv-contrib-python-headless") from exc
    module = getattr(cv2, "ppf_match_3d", None)
    if module is None or not hasattr(module, "PPF3DDetector"):
        raise PsorrError(f"OpenCV {cv2.__version__} has no cv2.ppf_match_3d.PPF3DDetector; "
                         "pip install opencv-contrib-python-headless (the contrib build, not opencv-python)")
    return cv2


def _ppf_model(ppf, mesh: trimesh.Trimesh, p: OpencvPpfParams) -> tuple:
    """(detector, (N, 3) samples, (N, 3) normals) for one mesh, trained once per mesh and settings.

    The samples are a fixed function of the mesh (seed 0), not of the caller's rng, so a trained
    detector (the expensive, offline step of Drost's method) is reused across calls."""
    key = (hashlib.sha1(mesh.vertices.tobytes() + mesh.faces.tobytes()).hexdigest(), p.model_samples,
           p.relative_sampling_step, p.relative_distance_step, p.num_angles)
    if key not in _PPF_CACHE:
        points, normals = _sample_model(mesh, p.model_samples, np.random.default_rng(0))
        detector = ppf.PPF3DDetector(p.relative_sampling_step, p.relative_distance_step, p.num_angles)
        detector.trainModel(np.hstack((points, normals)).astype(np.float32))
        _PPF_CACHE[key] = (detector, points, normals)
    return _PPF_CACHE[key]


def _ppf_refine(icp, T: np.ndarray, samples: np.ndarray, normals: np.ndarray, scene_pc: np.ndarray,
                p: OpencvPpfParams) -> tuple[np.ndarray, float]:
    """ICP of the camera-facing model samples (N, 3) posed by T (4, 4) against the scene points (M, 6)
    within icp_crop model diameters of the posed centroid. Returns (pose, OpenCV's residual; inf on failure)."""
    facing = _facing_camera(T, samples, normals)
    centroid = _posed(T, samples.mean(axis=0)[None])[0]
    near = np.linalg.norm(scene_pc[:, :3] - centroid, axis=1) < p.icp_crop * model_diameter(samples)
    if facing.sum() < 10 or near.sum() < 10:
        return T, np.inf
    src = np.hstack((_posed(T, samples[facing]), normals[facing] @ T[:3, :3].T)).astype(np.float32)
    _, residual, dT = icp.registerModelToScene(src, np.ascontiguousarray(scene_pc[near]))
    T = np.asarray(dT, np.float64) @ T
    u, _, vt = np.linalg.svd(T[:3, :3])  # float32 round trips leave the rotation slightly off
    T[:3, :3], T[3] = u @ np.diag((1.0, 1.0, np.linalg.det(u @ vt))) @ vt, (0.0, 0.0, 0.0, 1.0)
    return T, float(residual)


def _nms(found: list[tuple], factor: float) -> list[Detection]:
    """found: (Detection, centroid (3,), diameter); keep the best-scored of each group of close ones."""
    kept = []
    for det, centroid, diameter in sorted(found, key=lambda f: -f[0].score):
        if all(np.linalg.norm(centroid - c) >= factor * min(diameter, d) for _, c, d in kept):
            kept.append((det, centroid, diameter))
    return [k[0] for k in kept]


def _ppf_detect(ppf, models: dict[str, trimesh.Trimesh], scene: np.ndarray, p: OpencvPpfParams) -> list[tuple]:
    """(Detection, posed centroid (3,), diameter) of every accepted hypothesis in the scene points (M, 3)."""
    scene_pc = np.hstack((scene, _camera_normals(scene, p.normal_knn))).astype(np.float32)
    tree, found = cKDTree(scene), []
    icp = ppf.ICP(p.icp_iterations, p.icp_tolerance, p.icp_rejection_scale, p.icp_levels)
    for name, mesh in sorted(models.items()):
        detector, samples, normals = _ppf_model(ppf, mesh, p)
        diameter, centroid = model_diameter(samples), samples.mean(axis=0)
        for result in list(detector.match(scene_pc, p.scene_sample_step, p.scene_distance))[:p.top_k]:
            if result.numVotes < p.min_votes:
                continue
            T, residual = _ppf_refine(icp, np.asarray(result.pose, np.float64), samples, normals, scene_pc, p)
            if residual > p.max_residual:
                continue
            explained, support, seen = _verify(T, samples, normals, scene, tree, p.support_distance)
            score = 0.5 * (explained + support)
            if score >= p.min_score:
                found.append((Detection(name, T, score, seen), _posed(T, centroid[None])[0], diameter))
    return found


def recognize_ppf_opencv(models: dict[str, trimesh.Trimesh], cloud: PointCloud, rng: np.random.Generator,
                         params: OpencvPpfParams | None = None) -> list[Detection]:
    """OpenCV's PPF3DDetector (Drost et al. 2010) + its ICP on the cloud without the table plane.

    Args:
        models: name -> mesh (metres, model frame). Each is trained once per process and settings.
        cloud: N points (metres, camera frame, camera at the origin); NaN rows are ignored.
        rng: the only source of randomness (the table-plane RANSAC's seed).
    Returns:
        Detections sorted by score: T_cloud_model (4, 4); score = mean of the share of the scene points
        near the posed model that it explains and the share of its visible samples matched by the scene,
        both within support_distance (see _verify); visible_fraction = the share of all samples matched.
    Raises:
        PsorrError: OpenCV's contrib modules are missing (pip install opencv-contrib-python-headless).
    """
    cv2 = _cv2()
    ppf, p = cv2.ppf_match_3d, params or OpencvPpfParams()
    if not models:
        raise InvalidInputError("models is empty; give at least one name -> trimesh.Trimesh")
    points = _valid_points(cloud)
    with _threads(p.threads, cv2), o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        _seed(rng)
        scene, _ = _remove_table(points, p.voxel, p.plane_distance, p.plane_iterations)
        found = _ppf_detect(ppf, models, scene, p) if len(scene) >= 10 else []
    return _nms(found, p.nms_factor)
