"""The compiled cost grid of the resting-pose search against the same costs written out in numpy."""

from __future__ import annotations

import numpy as np
import pytest

from psorr.geometry.distance_field import DistanceField
from psorr.hypotheses.outline import _turns
from psorr.hypotheses.resting_costs import resting_costs


def _numpy_costs(M, t, points, shifts, R, silhouette, model: DistanceField, patch: DistanceField, cap):
    """The definition: every pose's points posed as arrays, looked up in the fields, capped, squared, averaged."""
    moved = np.einsum("aij,nj->ani", M, points)[:, None] - np.einsum("aij,sj->asi", M, shifts)[:, :, None] + t
    on_model = np.minimum(model(moved).astype(float), cap)
    posed = np.einsum("aij,mj->ami", R, silhouette)[:, None] + shifts[None, :, None, :2]
    past = np.minimum(patch(posed).astype(float), cap)
    return ((on_model**2).mean(axis=-1) + (past**2).mean(axis=-1)) / cap**2


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_compiled_costs_equal_the_numpy_definition(seed):
    rng = np.random.default_rng(seed)
    cap, cell = 0.008, 0.002
    # Fields of random point sets; queries reach past both grids, which must read the truncation.
    model = DistanceField.of_points(rng.uniform(-0.03, 0.03, (400, 3)), cell, cap)
    patch = DistanceField.of_points(rng.uniform(-0.02, 0.02, (300, 2)), cell, cap)
    angles = np.radians(np.arange(0.0, 360.0, 20.0))
    T = np.eye(4)
    T[:3, :3] = _turns(np.array([0.7]))[0] @ np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = rng.uniform(-0.01, 0.01, 3)
    M = T[:3, :3] @ _turns(-angles)
    points = rng.uniform(-0.05, 0.05, (90, 3))
    shifts = np.column_stack([rng.uniform(-0.01, 0.01, (7, 2)), np.zeros(7)])
    silhouette = rng.uniform(-0.04, 0.04, (60, 2))
    R = _turns(angles)[:, :2, :2]
    compiled = resting_costs(M, T[:3, 3], points, shifts, R, silhouette, model.distances, model.low, model.cell,
                             patch.distances, patch.low, patch.cell, cap)
    expected = _numpy_costs(M, T[:3, 3], points, shifts, R, silhouette, model, patch, cap)
    assert compiled.shape == (len(angles), len(shifts))
    np.testing.assert_allclose(compiled, expected, rtol=0, atol=1e-12)
    assert 0.0 < compiled.min() and compiled.max() <= 2.0  # both terms capped at 1 each
