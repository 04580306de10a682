"""Minimum-volume oriented bounding boxes of primitive inliers.

A primitive fixes one box axis (a plane's normal, a cylinder's axis); the
other two come from the minimum-area rectangle around the points projected
onto the orthogonal plane, found by rotating calipers over the 2-D convex hull
(the optimal rectangle has a side flush with a hull edge).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from psorr.geometry.columns import column_max, column_min
from psorr.geometry.rotations import cross
from psorr.types import OrientedBox


def orthonormal_frame(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (3,) that make a right-handed frame with the unit ``axis`` (3,)."""
    helper = (1.0, 0.0, 0.0) if abs(axis[0]) < 0.9 else (0.0, 1.0, 0.0)
    a = axis.tolist()
    u = cross(a, helper)
    u /= np.linalg.norm(u)
    return u, cross(a, u.tolist())


def min_area_rectangle(xy: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Minimum-area rectangle of (N, 2) points: (centre (2,), angle rad, size (2,))."""
    try:
        hull = xy[ConvexHull(xy).vertices]
    except (QhullError, ValueError):
        hull = xy  # collinear or too few points: every edge direction is tried below
    edges = np.diff(np.vstack([hull, hull[:1]]), axis=0)
    angles = np.unique(np.mod(np.arctan2(edges[:, 1], edges[:, 0]), np.pi / 2))
    cos, sin = np.cos(angles), np.sin(angles)
    # Coordinates of every hull point in every candidate frame: (A, H).
    along = np.outer(cos, hull[:, 0]) + np.outer(sin, hull[:, 1])
    across = -np.outer(sin, hull[:, 0]) + np.outer(cos, hull[:, 1])
    lo_a, hi_a = along.min(1), along.max(1)
    lo_c, hi_c = across.min(1), across.max(1)
    area = (hi_a - lo_a) * (hi_c - lo_c)
    best = int(np.argmin(area))
    ca, cc = (lo_a[best] + hi_a[best]) / 2, (lo_c[best] + hi_c[best]) / 2
    c, s = cos[best], sin[best]
    centre = np.array([c * ca - s * cc, s * ca + c * cc])
    return centre, float(angles[best]), np.array([hi_a[best] - lo_a[best], hi_c[best] - lo_c[best]])


def box_around_axis(points: np.ndarray, axis: np.ndarray, hull_points: np.ndarray | None = None) -> OrientedBox:
    """The minimum-volume box of (N, 3) points with one side along `axis`.

    `hull_points` (for example voxel centroids of the same points) may stand in
    for `points` when choosing the rectangle's orientation, which is the costly
    part; the extents are always those of every point.
    """
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    u, v = orthonormal_frame(axis)
    source = points if hull_points is None else hull_points
    _, angle, _ = min_area_rectangle(np.column_stack([source @ u, source @ v]))
    c, s = np.cos(angle), np.sin(angle)
    frame = np.column_stack([c * u + s * v, -s * u + c * v, axis])
    local = points @ frame
    lo, hi = column_min(local), column_max(local)
    return OrientedBox(frame @ ((lo + hi) / 2), frame, hi - lo)
