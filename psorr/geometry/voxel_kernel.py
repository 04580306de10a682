"""The compiled pass of :func:`psorr.geometry.voxels.voxel_means`, in a module of its own: numba's import
takes 0.3 s, so only a caller that downsamples pays it."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def sorted_means(sorted_keys: np.ndarray, order: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(M, 3) the mean of the ``points`` (N, 3) of each run of equal ``sorted_keys`` (N,), the points taken
    in ``order`` (N,), which sorts the keys."""
    n = len(sorted_keys)
    out = np.empty((n, 3))
    m, count, last = -1, 0, 0
    for i in range(n):
        if i == 0 or sorted_keys[i] != last:
            if m >= 0:
                out[m] /= count
            m += 1
            count = 0
            last = sorted_keys[i]
            out[m] = 0.0
        p = order[i]
        out[m, 0] += points[p, 0]
        out[m, 1] += points[p, 1]
        out[m, 2] += points[p, 2]
        count += 1
    if m >= 0:
        out[m] /= count
    return out[:m + 1]
