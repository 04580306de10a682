"""The diameter of a point set: the largest distance between two of its points, exactly, in bounded memory.

All pairs at once would take N^2 / 2 distances (100 GB for the 160,000 vertices of a finely tessellated
knob or ball), and on a ball every vertex is a corner of the hull, so the hull does not thin them either.
With offsets x and y of two points from a centre, the parallelogram law gives |x + y|^2 = 2|x|^2 + 2|y|^2
- |x - y|^2. A pair longer than a known length L through point y must therefore end within
sqrt(2 R^2 + 2|y|^2 - L^2) of -y, R the largest offset: a small ball about the antipode, found in a k-d
tree. L starts as the longest of a few farthest-point sweeps, which on most shapes is already the diameter,
and grows as pairs are measured; points are taken farthest from the centre first, and once a point's ball
is empty, so are those of all nearer ones.

The balls are small only where the shape is nearly centrally symmetric about the centre. A three-lobed knob
reaches 1.27 times half its diameter from its box's centre, and each ball of its 590,000 finely tessellated
vertices held 350,000 points; its hull has 1,757 corners. So the search runs over the hull's corners (the
diameter's two ends are among them), which costs 1.7 s on a geodesic ball of 163,842 vertices, where the
hull keeps them all, and 0.2 s on the knob.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree
from scipy.spatial.distance import pdist

from psorr.errors import InvalidInputError

_ALL_PAIRS = 2048  # up to this many points every pair is measured: 2 million distances
_QUERIES = 4096  # points whose antipodal balls are searched at a time...
_PAIRS = 4_000_000  # ...and at most about this many pairs they hold measured at a time
_SWEEPS = 4  # farthest-point sweeps for the first lower bound
_SLACK = 1e-9  # relative: the balls are widened by rounding's worth, so that no pair on their rim is lost


def diameter(points) -> float:
    """The largest distance between two of (N, 3) ``points`` (N >= 2), in their unit."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 2:
        raise InvalidInputError(f"a diameter needs at least two 3-D points, got shape {points.shape}")
    points = np.unique(points, axis=0)  # an unmerged mesh repeats its vertices; each copy would be searched
    if len(points) < 2:
        return 0.0
    if len(points) > _ALL_PAIRS:
        points = _hull_corners(points)
    if len(points) <= _ALL_PAIRS:
        return float(pdist(points).max())
    offsets = points - 0.5 * (points.min(axis=0) + points.max(axis=0))
    reach = np.linalg.norm(offsets, axis=1)
    widest, (best, pair) = float(reach.max()), _swept(points)
    tree = cKDTree(offsets)
    order, start = np.argsort(-reach, kind="stable"), 0
    while start < len(order):
        block = order[start:start + _QUERIES]
        squared = 2 * widest**2 + 2 * reach[block] ** 2 - best**2  # non-increasing along the block
        hopeful = squared > 0
        if not hopeful.any():
            break  # the farthest point left has an empty ball, and so has every nearer one
        start += len(block)
        block, radii = block[hopeful], np.sqrt(squared[hopeful]) * (1 + _SLACK) + _SLACK * widest
        counts = tree.query_ball_point(-offsets[block], radii, return_length=True)
        for taken in _batches(counts):  # counted once per block, measured a batch at a time
            length, ends = _longest(tree, points, offsets, block[taken], radii[taken], counts[taken])
            if length > best:
                best, pair = length, ends
    # The pair measured as every pair is (pdist): the same value to the bit, whichever way it was found.
    return float(pdist(points[list(pair)])[0])


def _batches(counts: np.ndarray):
    """Slices of consecutive balls that hold about ``_PAIRS`` points together (a ball holding more, alone)."""
    first, held = 0, 0
    for k, count in enumerate(counts.tolist()):
        if held and held + count > _PAIRS:
            yield slice(first, k)
            first, held = k, 0
        held += count
    if first < len(counts):
        yield slice(first, len(counts))


def _hull_corners(points: np.ndarray) -> np.ndarray:
    """The corners of the convex hull of (N, 3) ``points``, among which the diameter's ends lie; all the points
    when Qhull cannot build a hull (they lie in a plane or on a line)."""
    try:
        return points[np.sort(ConvexHull(points).vertices)]
    except QhullError:
        return points


def _longest(tree: cKDTree, points: np.ndarray, offsets: np.ndarray, block: np.ndarray, radii: np.ndarray,
             counts: np.ndarray) -> tuple[float, tuple[int, int]]:
    """(length, its two points' indices) of the longest pair between each of the ``block`` points and the points
    in its antipodal ball (0 and no pair if none)."""
    if not counts.sum():
        return 0.0, (0, 0)
    found = tree.query_ball_point(-offsets[block], radii, return_sorted=False)
    ends = np.concatenate([np.asarray(f, dtype=np.int64) for f in found])
    starts = np.repeat(block, counts)
    lengths = np.linalg.norm(points[ends] - points[starts], axis=1)
    k = int(np.argmax(lengths))
    return float(lengths[k]), (int(starts[k]), int(ends[k]))


def _swept(points: np.ndarray) -> tuple[float, tuple[int, int]]:
    """A lower bound of the diameter, and its pair: the farthest point from the farthest point, a few times over."""
    here, best, pair = 0, 0.0, (0, 0)
    for _ in range(_SWEEPS):
        distances = np.linalg.norm(points - points[here], axis=1)
        far = int(np.argmax(distances))
        if distances[far] > best:
            best, pair = float(distances[far]), (here, far)
        here = far
    return best, pair
