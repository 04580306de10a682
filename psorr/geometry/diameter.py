"""The diameter of a point set: the largest distance between two of its points, exactly, in bounded memory.

The farthest pair lies on the convex hull, usually a small share of a mesh's vertices; but every vertex of a
smooth convex part (a finely tessellated knob, a ball) is a hull corner, and all their pairs at once would
take N^2 / 2 distances (100 GB for 160,000 corners). A pair no longer than a known one is passed over: with
the hull's centroid c and R its largest distance to a corner, no pair through a corner p is longer than
|p - c| + R, so only corners with |p - c| + R above the longest pair found by a few farthest-point sweeps can
do better, and only pairs of those are measured, a block at a time.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError
from scipy.spatial.distance import cdist, pdist

from psorr.errors import InvalidInputError

_BLOCK = 2048  # corners measured against the rest at a time: 2048 x N distances in memory
_SWEEPS = 4  # farthest-point sweeps for the first lower bound


def hull_corners(points: np.ndarray) -> np.ndarray:
    """The corners of the convex hull of (N, 3) ``points``; all of them when they are flat or degenerate."""
    try:
        return points[ConvexHull(points).vertices]
    except QhullError:
        try:  # flat: joggled, the hull still names the extreme points
            return points[ConvexHull(points, qhull_options="QJ").vertices]
        except QhullError:
            return points


def diameter(points) -> float:
    """The largest distance between two of (N, 3) ``points`` (N >= 2), in their unit."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 2:
        raise InvalidInputError(f"a diameter needs at least two 3-D points, got shape {points.shape}")
    corners = hull_corners(points)
    if len(corners) <= _BLOCK:
        return float(pdist(corners).max())
    best = _swept(corners)
    centre = corners.mean(axis=0)
    reach = np.linalg.norm(corners - centre, axis=1)
    hopeful = corners[reach + reach.max() > best]
    for start in range(0, len(hopeful), _BLOCK):
        best = max(best, float(cdist(hopeful[start:start + _BLOCK], hopeful[start:]).max()))
    return best


def _swept(points: np.ndarray) -> float:
    """A lower bound of the diameter: the farthest point from the farthest point, a few times over."""
    here, best = 0, 0.0
    for _ in range(_SWEEPS):
        distances = np.linalg.norm(points - points[here], axis=1)
        here = int(np.argmax(distances))
        best = max(best, float(distances[here]))
    return best
