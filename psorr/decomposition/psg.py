"""Edges of the primitive shape graph.

Two primitives are neighbours when their inliers (at voxel resolution) come
within the adjacency gap of each other; a radius search finds every such
pair, even across small fragments between two faces. A sensor never sees where a lying cylinder touches the
surface below it: the contact line hides under the cylinder, so the nearest
visible points of the two are up to about a radius apart. A cylinder tangent
to a plane, with its axis parallel to it and its points within a radius plus
the gap of the plane's points, is therefore a neighbour too.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from psorr.types import Primitive, PrimitiveKind


def _tangent(plane: Primitive, cylinder: Primitive, max_tilt_deg: float, tolerance: float) -> bool:
    axis_tilt = np.degrees(np.arcsin(min(1.0, abs(cylinder.axis @ plane.normal))))
    axis_height = abs(plane.normal @ cylinder.axis_point + plane.offset)
    return axis_tilt < max_tilt_deg and abs(axis_height - cylinder.radius) < tolerance


def close_pairs(voxel_labels, voxel_points, gap: float) -> set[tuple[int, int]]:
    """Label pairs (a, b), a < b, with voxels of a and b within `gap` metres."""
    labelled = np.flatnonzero(voxel_labels >= 0)
    near = cKDTree(voxel_points[labelled]).query_pairs(gap, output_type="ndarray")
    a, b = voxel_labels[labelled[near[:, 0]]], voxel_labels[labelled[near[:, 1]]]
    differ = a != b
    lo, hi = np.minimum(a[differ], b[differ]), np.maximum(a[differ], b[differ])
    return set(zip(lo.tolist(), hi.tolist()))


def graph_edges(primitives, voxel_labels, voxel_points, gap: float) -> set[tuple[int, int]]:
    """Edges (i, j), i < j, between final primitives.

    Args:
        primitives: the final primitives; voxel_labels (M,) maps voxels to them (-1: none).
        voxel_points: (M, 3) voxel centroids.
        gap: metres within which inliers make neighbours.
    """
    pairs = close_pairs(voxel_labels, voxel_points, gap)
    planes = [i for i, p in enumerate(primitives) if p.kind is PrimitiveKind.PLANE]
    cylinders = [i for i, p in enumerate(primitives) if p.kind is PrimitiveKind.CYLINDER]
    trees = {}
    for c in cylinders:
        cyl = primitives[c]
        tolerance = max(0.005, 0.15 * cyl.radius)
        for p in planes:
            if (min(p, c), max(p, c)) in pairs or not _tangent(primitives[p], cyl, 10.0, tolerance):
                continue
            if p not in trees:
                trees[p] = cKDTree(voxel_points[voxel_labels == p])
            nearest, _ = trees[p].query(voxel_points[voxel_labels == c], k=1,
                                        distance_upper_bound=cyl.radius + gap)
            if np.isfinite(nearest).any():
                pairs.add((min(p, c), max(p, c)))
    return pairs
