"""A model's near-symmetries: turns and slides that map it almost onto itself, found once per model.

A sheet-metal tray with a connector window at one end is, to a point-pair matcher, the same
tray turned end for end. :func:`near_symmetries` finds the half turns about its principal axes
(through the centroid of its samples), each settled onto the model by ICP, that move its surface
by little on average (an L bracket's legs swap about their bisector, a few degrees off its
principal axes); exact symmetries qualify too, and :func:`exact_symmetries` tells them apart.
:func:`near_continuous_axis` finds an axis about which any turn is a near-symmetry (a flanged hub,
whose yaw only its bolt holes fix). :func:`near_uniform_direction` finds a direction along which the
part slides almost onto itself (a U-channel along its length, which only its two end faces fix).
Choosing between such poses in a scene is :mod:`psorr.acceptance.ambiguity`'s work.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from psorr.geometry.rotations import turn
from psorr.types import PrimitiveKind
from psorr.verification.depth_compare import DepthRenderer

NEAR_MEAN_DISTANCE = 0.03  # x model diameter: turns moving the surface less than this on average are near-symmetries
EXACT_DISTANCE = 2e-4  # m: a turn moving no sample further than this from the mesh is an exact symmetry
# m: a half turn moving no sample further than this from the mesh is a symmetry in all but its facets (a
# round part's tessellation moves 0.6 mm); the least feature that breaks one in the catalog moves 7 mm.
FACET_DISTANCE = 1e-3
AXIS_TEST_DEGREES = (7.0, 19.0, 37.0, 90.0, 143.0)  # turns that must all be near-symmetries for a near-continuous axis
# A slide by TEST_SHIFT x diameter that moves the surface by less than UNIFORM_LIMIT x the slide on average
# (90% of the surface slides onto itself) makes a direction near-uniform.
TEST_SHIFT, UNIFORM_LIMIT = 0.05, 0.1
# A half turn that moves fewer than FEATURE_SHARE of the samples further than FEATURE_MOVE from the surface
# is exact but for small features (the chassis' window and gland hole).
FEATURE_MOVE, FEATURE_SHARE = 0.002, 0.1


def near_symmetries(points: np.ndarray, diameter: float, limit: float = NEAR_MEAN_DISTANCE) -> np.ndarray:
    """(K, 4, 4) model-frame near-symmetries S: half turns about principal axes through the samples'
    centroid, each settled by ICP of S(points) onto points, whose mean nearest-sample distance
    is below ``limit`` x ``diameter``; one per distinct turn, and K may be 0.

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
        # A part that is not quite symmetric (an L bracket with legs of 60 and 50 mm) has its
        # principal axes a few degrees off the turn that swaps its halves; settle onto that turn.
        S, distance = _settled(S, subset, tree)
        duplicate = any(np.linalg.norm(S[:3, :3] - F[:3, :3]) < 0.1 for F in found)
        if distance.mean() < limit * diameter and not duplicate:
            found.append(S)
    return np.array(found).reshape(-1, 4, 4)


def _settled(S: np.ndarray, points: np.ndarray, tree: cKDTree, iterations: int = 15) -> tuple[np.ndarray, np.ndarray]:
    """The self-map S (4, 4) refined by point-to-point ICP of S(points) onto the model's own
    samples (``tree``), and the final nearest-sample distances (N,) in metres."""
    sparse = points[::3]  # the fit needs far fewer points than the final distances
    for _ in range(iterations):
        moved = sparse @ S[:3, :3].T + S[:3, 3]
        _, nearest = tree.query(moved)
        target = tree.data[nearest]
        mu_m, mu_t = moved.mean(axis=0), target.mean(axis=0)
        U, _, Vt = np.linalg.svd((moved - mu_m).T @ (target - mu_t))
        D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
        step = np.eye(4)
        step[:3, :3] = Vt.T @ D @ U.T
        step[:3, 3] = mu_t - step[:3, :3] @ mu_m
        S = step @ S
        if np.abs(step[:3, 3]).max() < 1e-6 and np.trace(step[:3, :3]) > 3.0 - 1e-10:
            break  # settled
    distance, _ = tree.query(points @ S[:3, :3].T + S[:3, 3])
    return S, distance


def near_continuous_axis(model, renderer: DepthRenderer,
                         limit: float = NEAR_MEAN_DISTANCE) -> tuple[np.ndarray, np.ndarray] | None:
    """The axis (a point (3,) on it, its direction (3,)) about which every test turn of ``model`` is a
    near-symmetry (mean distance below ``limit`` x diameter) but not all are exact symmetries (a
    turned sample lands more than ``EXACT_DISTANCE`` from the mesh), or None.

    A flanged hub is such a part: turned by any angle it is the same hub except for its bolt holes.
    A plain bushing is exactly symmetric, and no turn of it needs telling apart. The candidates are
    the model's cylinder axes and its principal axes; a cylinder's axis is the sharper estimate
    (principal axes of a squat part are barely determined), and the best-fitting candidate wins.
    """
    points = model.points
    centroid = points.mean(axis=0)
    _, axes = np.linalg.eigh(np.cov((points - centroid).T))
    candidates = [(p.axis_point, p.axis) for p in model.graph.primitives if p.kind is PrimitiveKind.CYLINDER]
    candidates += [(centroid, axis) for axis in axes.T]
    subset = points[:: max(1, len(points) // 1500)]
    best, best_mean = None, np.inf
    for point, axis in candidates:
        means, largest = [], 0.0
        for a in AXIS_TEST_DEGREES:  # most candidates fail the first turn or two
            distance = renderer.distance((subset - point) @ turn(axis, np.radians(a)).T + point)
            means.append(distance.mean())
            largest = max(largest, float(distance.max()))
            if means[-1] >= limit * model.diameter:
                break
        else:
            if largest > EXACT_DISTANCE and np.mean(means) < best_mean:
                best, best_mean = (np.asarray(point, float), np.asarray(axis, float)), float(np.mean(means))
    return best


def near_uniform_direction(model, renderer: DepthRenderer) -> np.ndarray | None:
    """The unit direction (3,), model frame, among the principal axes of ``model``'s samples, along
    which a slide by TEST_SHIFT x diameter moves its surface least, if that is below UNIFORM_LIMIT x
    the slide on average; else None. Of the catalog only the U-channel has one (0.06); the chassis,
    whose end walls fix it, and the circuit board come next at 0.16 and 0.13."""
    points = model.points[:: max(1, len(model.points) // 1500)]
    _, axes = np.linalg.eigh(np.cov((points - points.mean(axis=0)).T))
    shift = TEST_SHIFT * model.diameter
    moved = np.array([renderer.distance(points + shift * axis).mean() for axis in axes.T]) / shift
    k = int(np.argmin(moved))
    return axes[:, k] if moved[k] < UNIFORM_LIMIT else None


def exact_symmetries(renderer: DepthRenderer, points: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """(K,) bool: does each turn (K, 4, 4) map every sample of ``points`` (N, 3) to within FACET_DISTANCE of
    the mesh? Such a turn is a symmetry: its poses are the same part, with nothing to tell apart."""
    subset = points[:: max(1, len(points) // 1500)]
    return np.array([renderer.distance(subset @ S[:3, :3].T + S[:3, 3]).max() <= FACET_DISTANCE for S in turns],
                    dtype=bool)


def exact_but_features(points: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """(K,) bool: does each turn (K, 4, 4) move fewer than FEATURE_SHARE of the model's ``points`` (N, 3)
    further than FEATURE_MOVE from the samples?"""
    tree = cKDTree(points)
    return np.array([(tree.query(points @ S[:3, :3].T + S[:3, 3])[0] > FEATURE_MOVE).mean() < FEATURE_SHARE
                     for S in turns], dtype=bool)
