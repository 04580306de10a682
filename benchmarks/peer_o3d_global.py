"""Open3D's global registration, as its tutorial builds it, as a peer of PSORR: per model, over the whole
scene without the table, FPFH features on a 5 mm voxel grid, RANSAC on feature matches
(registration_ransac_based_on_feature_matching), then point-to-plane ICP on the full clouds. A model's
pose is kept when it passes the point check the other peers use (:func:`peer_common.verify`).

The tutorial's settings, all in voxels: normals within 2, FPFH within 5 (at most 30 and 100
neighbours), RANSAC correspondences within 1.5 with its edge-length (0.9) and distance checkers,
100,000 iterations at 0.999 confidence, and ICP correspondences within 0.4.

`recognize_o3d_global(models, cloud, rng, params) -> list[Detection]`, called as
:func:`peer_fpfh.recognize_fpfh` is: at most one detection per model."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
import open3d as o3d
import trimesh
from peer_common import o3d_cloud, remove_table, sample_model, seed, threads, valid_points, verify
from scipy.spatial import cKDTree

from psorr.errors import InvalidInputError
from psorr.types import Detection, PointCloud

_REG = o3d.pipelines.registration


@dataclass(frozen=True)
class O3dGlobalParams:
    """Settings of the Open3D global-registration peer; distances in metres, ``*_factor``s in voxels.

    voxel: the grid of the scene and the models. plane_distance, plane_iterations: table removal, as
    in the other peers. model_samples: uniform surface samples per model (seed 0, with the mesh's
    normals). normal_*, feature_*, ransac_*, icp_*: the tutorial's (module docstring). support_distance,
    min_score: the point check, as the OpenCV peer's: the mean of the share of scene points near the
    posed model that it explains and the share of its visible samples the scene matches, within
    support_distance, must reach min_score. threads: Open3D threads in the call (1 repeats a seed exactly).
    """

    voxel: float = 0.005
    plane_distance: float = 0.006
    plane_iterations: int = 1000
    model_samples: int = 3000
    normal_radius_factor: float = 2.0
    normal_max_nn: int = 30
    feature_radius_factor: float = 5.0
    feature_max_nn: int = 100
    ransac_distance_factor: float = 1.5
    ransac_edge_length: float = 0.9
    ransac_mutual_filter: bool = True
    ransac_iterations: int = 100_000
    ransac_confidence: float = 0.999
    icp_distance_factor: float = 0.4
    support_distance: float = 0.006
    min_score: float = 0.6
    threads: int | None = 1


def _features(pcd: o3d.geometry.PointCloud, p: O3dGlobalParams):
    """The voxel grid of pcd, with normals (turned towards the camera at the origin when pcd has none),
    and its FPFH features."""
    down = pcd.voxel_down_sample(p.voxel)
    if not pcd.has_normals():
        down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(
            radius=p.normal_radius_factor * p.voxel, max_nn=p.normal_max_nn))
        down.orient_normals_towards_camera_location(np.zeros(3))
    feature = _REG.compute_fpfh_feature(down, o3d.geometry.KDTreeSearchParamHybrid(
        radius=p.feature_radius_factor * p.voxel, max_nn=p.feature_max_nn))
    return down, feature


_MODELS: dict[tuple, dict] = {}


def _model(mesh: trimesh.Trimesh, p: O3dGlobalParams) -> dict:
    """Samples, normals and their grid's features, once per mesh and settings (the offline step)."""
    key = (hashlib.sha1(mesh.vertices.tobytes() + mesh.faces.tobytes()).hexdigest(), p)
    if key not in _MODELS:
        points, normals = sample_model(mesh, p.model_samples, np.random.default_rng(0))
        full = o3d_cloud(points, normals)
        down, feature = _features(full, p)
        _MODELS[key] = {"points": points, "normals": normals, "full": full, "down": down, "feature": feature}
    return _MODELS[key]


def _register(model: dict, scene: dict, p: O3dGlobalParams) -> np.ndarray:
    """The tutorial's two steps: RANSAC on FPFH matches, then point-to-plane ICP. Returns T (4, 4) model -> cloud."""
    distance = p.ransac_distance_factor * p.voxel
    ransac = _REG.registration_ransac_based_on_feature_matching(
        model["down"], scene["down"], model["feature"], scene["feature"], p.ransac_mutual_filter, distance,
        _REG.TransformationEstimationPointToPoint(False), 3,
        [_REG.CorrespondenceCheckerBasedOnEdgeLength(p.ransac_edge_length),
         _REG.CorrespondenceCheckerBasedOnDistance(distance)],
        _REG.RANSACConvergenceCriteria(p.ransac_iterations, p.ransac_confidence))
    icp = _REG.registration_icp(model["full"], scene["full"], p.icp_distance_factor * p.voxel, ransac.transformation,
                                _REG.TransformationEstimationPointToPlane())
    return np.asarray(icp.transformation)


def recognize_o3d_global(models: dict[str, trimesh.Trimesh], cloud: PointCloud, rng: np.random.Generator,
                         params: O3dGlobalParams | None = None) -> list[Detection]:
    """Each model registered to the whole scene without the table; the poses that pass the point check.

    Args:
        models: name -> mesh (metres, model frame).
        cloud: N points (metres, camera frame, camera at the origin); NaN rows are ignored.
        rng: the only source of randomness (Open3D's seeds, one before each model's RANSAC).
    Returns:
        Detections sorted by score: T_cloud_model (4, 4); score = the point check's mean (see
        O3dGlobalParams); visible_fraction = the share of all the model's samples matched by the scene.
    """
    p = params or O3dGlobalParams()
    if not models:
        raise InvalidInputError("models is empty; give at least one name -> trimesh.Trimesh")
    points = valid_points(cloud)
    detections = []
    with threads(p.threads), o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        seed(rng)
        above, _ = remove_table(points, p.voxel, p.plane_distance, p.plane_iterations)
        if len(above) < 10:
            return []
        full = o3d_cloud(above)
        full.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(
            radius=p.normal_radius_factor * p.voxel, max_nn=p.normal_max_nn))
        full.orient_normals_towards_camera_location(np.zeros(3))
        down, feature = _features(o3d_cloud(above), p)
        scene, tree = {"full": full, "down": down, "feature": feature}, cKDTree(above)
        for name, mesh in sorted(models.items()):
            model = _model(mesh, p)
            seed(rng)
            T = _register(model, scene, p)
            explained, support, seen = verify(T, model["points"], model["normals"], above, tree, p.support_distance)
            if 0.5 * (explained + support) >= p.min_score:
                detections.append(Detection(name, T, 0.5 * (explained + support), seen))
    return sorted(detections, key=lambda d: -d.score)
