"""psorr.geometry.distance_field: truncated distances to point sets, in 2-D and 3-D."""

from __future__ import annotations

import numpy as np
import pytest

from psorr.geometry.distance_field import DistanceField


@pytest.mark.parametrize("dimensions", [2, 3])
def test_distances_match_the_nearest_point_within_a_cell(dimensions):
    rng = np.random.default_rng(0)
    points = rng.uniform(0.0, 0.05, (200, dimensions))
    field = DistanceField.of_points(points, cell=0.001, truncation=0.01)
    queries = rng.uniform(-0.02, 0.07, (500, dimensions))
    exact = np.minimum(np.linalg.norm(queries[:, None] - points[None], axis=2).min(axis=1), 0.01)
    # A query reads its cell's distance: off by at most a cell's diagonal either way.
    assert np.all(np.abs(field(queries) - exact) <= 0.001 * np.sqrt(dimensions) + 1e-9)


def test_queries_far_outside_the_grid_read_the_truncation():
    field = DistanceField.of_points(np.zeros((1, 3)), cell=0.002, truncation=0.008)
    far = np.array([[1.0, 0.0, 0.0], [-5.0, 3.0, 2.0], [0.0, 0.0, 0.0]])
    assert field(far).tolist() == pytest.approx([0.008, 0.008, 0.0])


def test_queries_of_any_leading_shape_keep_it():
    field = DistanceField.of_points(np.zeros((1, 2)), cell=0.001, truncation=0.005)
    assert field(np.zeros((4, 3, 7, 2))).shape == (4, 3, 7)
