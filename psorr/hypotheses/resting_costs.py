"""The resting-pose search's cost grid, compiled: every turn and shift of one resting shape over one patch.

The search (:mod:`psorr.hypotheses.outline`) scores about 400 poses of each of some 40 resting shapes a
scene, each pose by some 270 distance-field lookups. In numpy every pose's posed points and lookups were
arrays of their own, and the grid took 0.23 of a 0.9 s scene; this kernel walks the same grid without
them, 11 times faster, with the same costs to 1e-6 (numpy summed them in float32).
Measured: docs/decisions/0053-compiled-resting-costs.md.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _cell(x: float, low: float, cell: float, count: int) -> int:
    """The grid index of coordinate ``x`` on an axis from ``low`` in steps of ``cell``, clipped onto the
    ``count`` cells (a query outside reads the border, which holds the truncation)."""
    index = int((x - low) / cell)
    return 0 if index < 0 else (count - 1 if index > count - 1 else index)


@njit(cache=True)
def resting_costs(M: np.ndarray, t: np.ndarray, points: np.ndarray, shifts: np.ndarray, R: np.ndarray,
                  silhouette: np.ndarray, model_field: np.ndarray, model_low: np.ndarray, model_cell: float,
                  patch_field: np.ndarray, patch_low: np.ndarray, patch_cell: float, cap: float) -> np.ndarray:
    """(A, S) costs of a resting shape turned A ways and moved S ways over a patch.

    Pose (a, s) takes a patch point q (table frame) to the model point ``M[a] q - M[a] shifts[s] + t``, and a
    silhouette sample p to ``R[a] p + shifts[s, :2]``. Its cost is the mean square of the model field at the
    patch's ``points`` (N, 3), plus that of the patch field at the ``silhouette`` (K, 2), each distance
    capped at ``cap`` and the sum divided by cap^2.

    Args:
        M: (A, 3, 3); t: (3,); points: (N, 3); shifts: (S, 3); R: (A, 2, 2); silhouette: (K, 2); metres.
        model_field: (n0, n1, n2) distances from the grid corner ``model_low`` (3,) in cells of ``model_cell``.
        patch_field: (m0, m1) the same in two dimensions, from ``patch_low`` (2,).
    """
    A, S, N, K = M.shape[0], shifts.shape[0], points.shape[0], silhouette.shape[0]
    n0, n1, n2 = model_field.shape
    m0, m1 = patch_field.shape
    out = np.empty((A, S))
    turned, moved, posed = np.empty((N, 3)), np.empty((S, 3)), np.empty((K, 2))
    for a in range(A):
        for n in range(N):
            for r in range(3):
                turned[n, r] = M[a, r, 0] * points[n, 0] + M[a, r, 1] * points[n, 1] + M[a, r, 2] * points[n, 2]
        for s in range(S):
            for r in range(3):
                moved[s, r] = t[r] - (M[a, r, 0] * shifts[s, 0] + M[a, r, 1] * shifts[s, 1]
                                      + M[a, r, 2] * shifts[s, 2])
        for k in range(K):
            for r in range(2):
                posed[k, r] = R[a, r, 0] * silhouette[k, 0] + R[a, r, 1] * silhouette[k, 1]
        for s in range(S):
            on_model = 0.0
            for n in range(N):
                d = model_field[_cell(turned[n, 0] + moved[s, 0], model_low[0], model_cell, n0),
                                _cell(turned[n, 1] + moved[s, 1], model_low[1], model_cell, n1),
                                _cell(turned[n, 2] + moved[s, 2], model_low[2], model_cell, n2)]
                d = min(float(d), cap)
                on_model += d * d
            past = 0.0
            for k in range(K):
                d = patch_field[_cell(posed[k, 0] + shifts[s, 0], patch_low[0], patch_cell, m0),
                                _cell(posed[k, 1] + shifts[s, 1], patch_low[1], patch_cell, m1)]
                d = min(float(d), cap)
                past += d * d
            out[a, s] = (on_model / N + past / K) / (cap * cap)
    return out
