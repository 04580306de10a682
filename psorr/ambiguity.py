"""Near-symmetries: turns that map a model almost onto itself, and choosing between them in a scene.

A sheet-metal tray with a connector window at one end is, to a point-pair matcher, the same
tray turned end for end: every primitive has its twin. Verification at the primitive level
cannot tell the two poses apart, and the turned one is often accepted. The difference lies in
small features (a window, a gland hole, a row of holes) that only a dense point check sees.

:func:`near_symmetries` finds, per model, the half turns about its principal axes (through
the centroid of its samples) that move its surface by little on average; exact symmetries
qualify too, which is harmless. :func:`best_of_near_symmetries` re-fits each turned pose with
ICP and keeps whichever explains the scene clearly best under a dense point check. When the
features are hidden the two cannot be told apart, and the original pose is kept.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from psorr.verify import CheckParams, PoseCheck, SceneView, check_pose, refine_icp

NEAR_MEAN_DISTANCE = 0.03  # x model diameter: turns moving the surface less than this on average are near-symmetries
DENSE_CHECK = CheckParams(max_points=6000)
# A turned pose replaces the original only when it scores clearly better and contradicts the sensor
# less. In seeded single-part scenes the true pose beats its turned twin by 0.02-0.03; in clutter,
# where neighbours hide the end walls that tell them apart, the twin can win by 0.01 by chance.
SWITCH_MARGIN = 0.02


def near_symmetries(points: np.ndarray, diameter: float, limit: float = NEAR_MEAN_DISTANCE) -> np.ndarray:
    """(K, 4, 4) model-frame half turns S (about principal axes through the samples' centroid) with
    mean nearest-sample distance of S(points) to points below ``limit`` x ``diameter``; K may be 0.

    Args:
        points: (N, 3) even surface samples of the model, metres.
        diameter: the model's diameter, metres.
    """
    centroid = points.mean(axis=0)
    _, axes = np.linalg.eigh(np.cov((points - centroid).T))
    tree = cKDTree(points)
    subset = points[:: max(1, len(points) // 3000)]
    found = []
    for axis in axes.T:
        R = 2.0 * np.outer(axis, axis) - np.eye(3)  # a half turn about the axis
        S = np.eye(4)
        S[:3, :3], S[:3, 3] = R, centroid - R @ centroid
        distance, _ = tree.query(subset @ R.T + S[:3, 3])
        if distance.mean() < limit * diameter:
            found.append(S)
    return np.array(found).reshape(-1, 4, 4)


def best_of_near_symmetries(view: SceneView, model, T_cloud_model: np.ndarray, turns: np.ndarray,
                            icp_distance: float) -> tuple[np.ndarray, PoseCheck]:
    """The pose among ``T_cloud_model`` and ``T_cloud_model @ S`` (each S in ``turns``, ICP-refined)
    that explains the scene best under a dense point check, with that check; a turned pose must beat
    the incumbent by ``SWITCH_MARGIN`` in score and have fewer violations."""
    best_T = T_cloud_model
    best = check_pose(view, model.points, model.normals, T_cloud_model, DENSE_CHECK)
    for S in turns:
        T = refine_icp(view, model.points, model.normals, T_cloud_model @ S, icp_distance)
        T = refine_icp(view, model.points, model.normals, T, icp_distance / 3)
        check = check_pose(view, model.points, model.normals, T, DENSE_CHECK)
        if check.score > best.score + SWITCH_MARGIN and check.n_violation < best.n_violation:
            best_T, best = T, check
    return best_T, best
