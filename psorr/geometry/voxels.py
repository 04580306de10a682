"""Voxel downsampling, compiled: each occupied voxel's points replaced by their mean.

The same voxels, and the same means to rounding, as Open3D's ``PointCloud.voxel_down_sample``: the grid
is anchored half a voxel below the points' least corner. Open3D's hash map spent 140-190 ms on a
640x480 frame (a third of a scene view's making, docs/decisions/0064-compiled-voxel-means.md); a sort
of the voxel keys and one pass over them take about 50. The voxels come in the order of their keys, so
one cloud gives one order.
"""

from __future__ import annotations

import numpy as np

from psorr.errors import InvalidInputError


def voxel_means(points: np.ndarray, voxel: float) -> np.ndarray:
    """(M, 3) the mean of the ``points`` (N, 3, finite, metres) in each occupied cube of side ``voxel``
    metres, in the order of the voxels' grid keys."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise InvalidInputError(f"voxel_means takes (N, 3) points, got an array of shape {points.shape}")
    if not voxel > 0:
        raise InvalidInputError(f"voxel_means needs a voxel size > 0 metres, got {voxel!r}")
    if len(points) == 0:
        return np.zeros((0, 3))
    # Column by column: reductions over axis 0 of an (N, 3) array are several times slower.
    index = [np.floor((c - (c.min() - 0.5 * voxel)) / voxel).astype(np.int64)
             for c in (points[:, 0], points[:, 1], points[:, 2])]
    key = (index[0] * (int(index[1].max()) + 1) + index[1]) * (int(index[2].max()) + 1) + index[2]
    order = np.argsort(key, kind="stable")
    from psorr.geometry.voxel_kernel import sorted_means  # numba: imported by the first use

    return sorted_means(key[order], order, points)
