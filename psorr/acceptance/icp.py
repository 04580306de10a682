"""Point-to-plane ICP: Open3D's, and a damped one for when Open3D's runs away.

Point-to-plane ICP solves, each iteration, for the small motion that best moves the source
points onto the target's tangent planes. A part that shows only a cylinder, or a long channel,
leaves some motions unconstrained (sliding along the axis, rolling about it), and the 6x6 normal
equations are then nearly singular: an undamped solve turns noise into steps of centimetres along
them. Open3D's carried a pipe tee, whose branch was hidden, from its true pose to 0.9 diameters
off. :func:`point_to_plane` damps the equations towards the start pose (Levenberg-Marquardt with
the start as prior): a motion the planes do not constrain is not taken, and one they do is barely
slowed. It costs four times Open3D's, so :func:`register` runs it only when Open3D's moved the
points further than a well-posed fit can (RUNAWAY x the pairing distance, on average).
"""

from __future__ import annotations

import numpy as np
import open3d as o3d
from scipy.spatial import cKDTree

from psorr.geometry.open3d_threads import single_threaded
from psorr.geometry.rotations import cross, from_rotation_vector, rotation_vector
from psorr.verification.point_check import CheckParams, depth_tolerance, visible_model_pixels
from psorr.verification.scene_view import SceneView

DAMPING = 1e-2  # x the largest eigenvalue of the (scaled) normal equations, towards the pose held
STOP_STEP = 1e-5  # m, and radians x the source's radius: a step smaller than this has converged
RUNAWAY = 2.0  # x max_distance: an Open3D fit that moves the points further than this on average is redone
DAMPED_POINTS = 1000  # ... with about this many of its source points: six unknowns need no more
# Model points over the sensor's holes (a Kinect measures nothing on a small hub's side seen edge on, nor in
# a nearer edge's shadow) pair in ICP with whatever lies within reach instead: the flange, the table. Where
# they were 43-58% of a partly hidden hub's or bushing's visible points, the coarse ICP took the part from
# its true pose to 5-21 mm off, and the check then rejected it. Above this share they are left out of the
# coarse ICP. Over 72 clutter images, leaving them out of every coarse ICP found 4 parts more and 2 false
# detections more (brackets converged onto other parts' walls; 7 more when left out of the fine ICP too);
# above this share, 3 parts more and no false detection more (docs/decisions/0029-icp-hole-share.md).
HOLE_SHARE = 0.3


def register(source: np.ndarray, target: o3d.geometry.PointCloud, max_distance: float, iterations: int) -> np.ndarray:
    """The motion T (4, 4) that moves ``source`` (N, 3) onto ``target`` (points with normals): Open3D's
    point-to-plane ICP, or :func:`point_to_plane` where that one ran away."""
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(source))
    with single_threaded():
        result = o3d.pipelines.registration.registration_icp(
            cloud, target, max_distance, np.eye(4),
            o3d.pipelines.registration.TransformationEstimationPointToPlane(),
            o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=iterations))
    T = np.asarray(result.transformation)
    moved = np.linalg.norm(source @ T[:3, :3].T + T[:3, 3] - source, axis=1).mean()
    if moved <= RUNAWAY * max_distance:
        return T
    sparse = source[:: max(1, len(source) // DAMPED_POINTS)]
    return point_to_plane(sparse, np.asarray(target.points), np.asarray(target.normals), max_distance, iterations)


def point_to_plane(source: np.ndarray, target: np.ndarray, target_normals: np.ndarray, max_distance: float,
                   iterations: int = 30) -> np.ndarray:
    """The rigid motion T (4, 4) that moves ``source`` (N, 3) onto the planes of ``target`` (M, 3) with unit
    ``target_normals`` (M, 3), pairing each source point with its nearest target point within
    ``max_distance`` metres, damped towards no motion. Returns the identity when fewer than 6 points pair."""
    tree = cKDTree(target)
    centre = source.mean(axis=0)
    # Turns are solved for in units of the source's radius, so that one damping suits turns and slides.
    scale = max(float(np.sqrt(((source - centre) ** 2).sum(axis=1).mean())), 1e-6)
    R, t = np.eye(3), np.zeros(3)
    for _ in range(iterations):
        moved = source @ R.T + t
        distance, nearest = tree.query(moved, distance_upper_bound=max_distance)
        paired = np.isfinite(distance)
        if paired.sum() < 6:
            break
        p, q, n = moved[paired] - centre, target[nearest[paired]] - centre, target_normals[nearest[paired]]
        # The prior holds the start: what the planes do not constrain stays where the start put it.
        so_far = np.concatenate([rotation_vector(R) * scale, R @ centre + t - centre])
        turn, slide = damped_step(p, q, n, scale, prior=so_far)
        dR = from_rotation_vector(turn)
        # The step turns about the centre: p' = dR p + slide, in coordinates about it.
        R, t = dR @ R, dR @ (t - centre) + centre + slide
        if np.linalg.norm(slide) < STOP_STEP and np.linalg.norm(turn) * scale < STOP_STEP:
            break
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def damped_step(p: np.ndarray, q: np.ndarray, normals: np.ndarray, scale: float, weights: np.ndarray | None = None,
                prior: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The small motion, a turn (3,) in radians about the origin of ``p`` and ``q`` then a slide (3,) in metres,
    that best moves points ``p`` (N, 3) onto the planes through ``q`` (N, 3) with unit ``normals`` (N, 3), each
    pair weighted by ``weights`` (N,), damped (Levenberg-Marquardt). Turns are solved for in units of ``scale``
    (m, the points' radius), so that one damping suits turns and slides. Without ``prior`` the damping holds
    the current pose; with it, the motion (6,) back to the pose to hold (turn x scale, slide)."""
    # d(residual) / d(turn x scale, slide); np.cross spent 13% of the ICP on axis handling.
    J = np.column_stack([cross(p.T, normals.T).T / scale, normals])
    r = np.einsum("ij,ij->i", p - q, normals)
    weighted = J if weights is None else J * weights[:, None]
    H = weighted.T @ J
    damping = DAMPING * np.linalg.eigvalsh(H)[-1]
    pull = -weighted.T @ r if prior is None else -weighted.T @ r - damping * prior
    step = np.linalg.solve(H + damping * np.eye(6), pull)
    return step[:3] / scale, step[3:]


def refine_icp(view: SceneView, model_points, model_normals, T_cloud_model, max_distance: float,
               iterations: int = 30, reach: float = 0.03, max_points: int = 3000,
               skip_holes: bool = False) -> np.ndarray:
    """Point-to-plane ICP (:func:`psorr.acceptance.icp.register`) of (at most about ``max_points`` of) the model's
    visible points, less those a nearer measured surface hides, onto the scene points within ``reach``
    metres of them; returns the refined pose. With ``skip_holes``, the points where the sensor measured
    nothing (:attr:`SceneView.measured_near`) are left out too when they are more than HOLE_SHARE of them."""
    R, t = T_cloud_model[:3, :3], T_cloud_model[:3, 3]
    stride = max(1, len(model_points) // max_points)
    pts, nrm = model_points[::stride] @ R.T + t, model_normals[::stride] @ R.T
    visible, u, v = visible_model_pixels(view, pts, nrm)
    if len(visible):
        # Points a nearer surface hides would pair with that surface and drag the part onto it (a U-channel
        # under two others went from its true pose to 0.47 diameters off).
        z = pts[visible, 2]
        pixel = v * view.width + u
        keep = ~(z > view.depth[pixel] + depth_tolerance(z, CheckParams())) & ~view.out_of_sight[pixel]
        if skip_holes:
            measured = view.measured_near[pixel]
            if (keep & ~measured).sum() > HOLE_SHARE * keep.sum():
                keep &= measured
        visible = visible[keep]
    if len(visible) < 10:
        return T_cloud_model
    # A target cropped to the hypothesis keeps Open3D's per-call k-d tree small.
    centre = pts[visible].mean(axis=0)
    radius = reach + 0.5 * float(np.linalg.norm(np.ptp(pts[visible], axis=0)))
    target = view.icp_target(centre, radius)
    if len(target.points) < 10:
        return T_cloud_model
    return register(pts[visible], target, max_distance, iterations) @ T_cloud_model
