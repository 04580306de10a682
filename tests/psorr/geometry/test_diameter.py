"""The diameter of a point set (psorr.geometry.diameter) against every pair measured."""

import numpy as np
import pytest
import trimesh
from scipy.spatial.distance import pdist

from psorr.errors import InvalidInputError
from psorr.geometry.diameter import diameter


def _on_ellipsoid(rng, n: int) -> np.ndarray:
    """(n, 3) points on an ellipsoid of semi-axes 30, 21 and 15 mm: every one a corner of their hull."""
    directions = rng.normal(size=(n, 3))
    return directions / np.linalg.norm(directions, axis=1, keepdims=True) * (0.03, 0.021, 0.015)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_diameter_of_thousands_of_hull_corners_is_every_pairs_longest(seed):
    points = _on_ellipsoid(np.random.default_rng(seed), 5000)
    assert diameter(points) == pytest.approx(pdist(points).max(), rel=1e-12)


def test_a_ball_and_a_flat_or_small_set_are_measured_exactly():
    rng = np.random.default_rng(3)
    ball = rng.normal(size=(4000, 3))
    ball /= np.linalg.norm(ball, axis=1, keepdims=True)
    flat = np.column_stack([rng.uniform(size=(300, 2)), np.zeros(300)])
    for points in (ball, flat, rng.uniform(size=(40, 3)), np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 2.0]])):
        assert diameter(points) == pytest.approx(pdist(points).max(), rel=1e-12)


def test_a_finely_tessellated_smooth_part_is_measured_in_bounded_memory():
    points = _on_ellipsoid(np.random.default_rng(4), 200_000)  # all pairs at once: 160 GB
    assert diameter(points) == pytest.approx(0.06, rel=1e-3)


def test_a_ball_whose_every_vertex_is_a_hull_corner_is_measured_exactly():
    # Every vertex of a geodesic ball is a hull corner and every pair through the centre a diameter: the
    # hull prunes nothing and every bound ties, the worst case for a search that passes over pairs.
    vertices = trimesh.creation.icosphere(subdivisions=7, radius=0.03).vertices  # 163,842 vertices
    assert diameter(vertices) == pytest.approx(0.06, rel=1e-12)


def test_a_finely_tessellated_part_far_from_centrally_symmetric_is_measured():
    # A triangular prism reaches 1.3 times half its diameter from its box's centre, so each point's antipodal
    # ball held most of the 300,000 points (as a three-lobed knob's did) and the search did not end.
    triangle = [(0.0, 0.0), (0.04, 0.0), (0.02, 0.04 * np.sqrt(3) / 2)]
    prism = trimesh.Trimesh([(x, y, z) for z in (0.0, 0.01) for x, y in triangle]).convex_hull
    points = np.vstack([prism.vertices, trimesh.sample.sample_surface(prism, 300_000, seed=6)[0]])
    assert diameter(points) == pytest.approx(np.hypot(0.04, 0.01), rel=1e-12)  # corner to corner


def test_repeated_points_are_measured_once():
    rng = np.random.default_rng(5)
    distinct = rng.uniform(size=(10, 3))
    assert diameter(np.repeat(distinct, 1000, axis=0)) == pytest.approx(pdist(distinct).max(), rel=1e-12)
    assert diameter(np.zeros((5, 3))) == 0.0


def test_fewer_than_two_points_are_refused():
    with pytest.raises(InvalidInputError, match="at least two 3-D points"):
        diameter(np.zeros((1, 3)))
