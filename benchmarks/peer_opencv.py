"""Drost et al.'s point pair features as a peer of PSORR: OpenCV's cv2.ppf_match_3d.PPF3DDetector,
refined by its ICP, on the scene without the table. Needs the optional extra:
pip install opencv-contrib-python-headless (or pip install -e ".[bench]").

`recognize_ppf_opencv(models, cloud, rng, params) -> list[Detection]`, called as
:func:`peer_fpfh.recognize_fpfh` is."""

from __future__ import annotations

import hashlib

import numpy as np
import open3d as o3d
import trimesh
from peer_common import (
    camera_normals,
    facing_camera,
    posed_points,
    remove_table,
    sample_model,
    seed,
    threads,
    valid_points,
    verify,
)
from scipy.spatial import cKDTree

from psorr.errors import InvalidInputError, PsorrError
from psorr.synthetic.catalog import model_diameter
from psorr.types import Detection, PointCloud


class OpencvPpfParams:
    """Settings of the OpenCV PPF peer; distances in metres, `relative_*` in model diameters.

    voxel, plane_distance, plane_iterations: table removal as in FpfhParams. model_samples: surface
    samples per model handed to training. relative_sampling_step, relative_distance_step, num_angles:
    PPF3DDetector's training grid. scene_sample_step: share of the sampled scene points used as
    reference points; scene_distance: the scene's sampling step. normal_knn: neighbours for scene
    normals. top_k: hypotheses per model refined by ICP. icp_*: cv2.ppf_match_3d.ICP settings.
    support_distance: a model sample or scene point is matched when the other is this near (see verify).
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
        points, normals = sample_model(mesh, p.model_samples, np.random.default_rng(0))
        detector = ppf.PPF3DDetector(p.relative_sampling_step, p.relative_distance_step, p.num_angles)
        detector.trainModel(np.hstack((points, normals)).astype(np.float32))
        _PPF_CACHE[key] = (detector, points, normals)
    return _PPF_CACHE[key]


def _ppf_refine(icp, T: np.ndarray, samples: np.ndarray, normals: np.ndarray, scene_pc: np.ndarray,
                p: OpencvPpfParams) -> tuple[np.ndarray, float]:
    """ICP of the camera-facing model samples (N, 3) posed by T (4, 4) against the scene points (M, 6)
    within icp_crop model diameters of the posed centroid. Returns (pose, OpenCV's residual; inf on failure)."""
    facing = facing_camera(T, samples, normals)
    centroid = posed_points(T, samples.mean(axis=0)[None])[0]
    near = np.linalg.norm(scene_pc[:, :3] - centroid, axis=1) < p.icp_crop * model_diameter(samples)
    if facing.sum() < 10 or near.sum() < 10:
        return T, np.inf
    src = np.hstack((posed_points(T, samples[facing]), normals[facing] @ T[:3, :3].T)).astype(np.float32)
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
    scene_pc = np.hstack((scene, camera_normals(scene, p.normal_knn))).astype(np.float32)
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
            explained, support, seen = verify(T, samples, normals, scene, tree, p.support_distance)
            score = 0.5 * (explained + support)
            if score >= p.min_score:
                found.append((Detection(name, T, score, seen), posed_points(T, centroid[None])[0], diameter))
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
        both within support_distance (see verify); visible_fraction = the share of all samples matched.
    Raises:
        PsorrError: OpenCV's contrib modules are missing (pip install opencv-contrib-python-headless).
    """
    cv2 = _cv2()
    ppf, p = cv2.ppf_match_3d, params or OpencvPpfParams()
    if not models:
        raise InvalidInputError("models is empty; give at least one name -> trimesh.Trimesh")
    points = valid_points(cloud)
    with threads(p.threads, cv2), o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        seed(rng)
        scene, _ = remove_table(points, p.voxel, p.plane_distance, p.plane_iterations)
        found = _ppf_detect(ppf, models, scene, p) if len(scene) >= 10 else []
    return _nms(found, p.nms_factor)
