"""Creases (psorr.segment.convexity): a valley is concave and a ridge is not, crease voxels grow back
into the parts around them, and parts stay apart only where most of their contact is a crease."""

import numpy as np

from psorr.segment.convexity import concave_edges, grow_into, join_unless_concave, median_bend


def _fold(depth_sign: float):
    """Two strips of voxels meeting at x = 0, 1 m in front of the sensor, tilted 45 degrees each way:
    a valley (depth_sign +1: the middle is farthest) or a ridge (-1). Normals face the sensor."""
    x = np.linspace(-0.02, 0.02, 9)
    centroids = np.column_stack([x, np.zeros_like(x), 1.0 + depth_sign * (0.02 - np.abs(x))])
    normals = np.column_stack([-depth_sign * np.sign(x), np.zeros_like(x), -np.ones_like(x)]) / np.sqrt(2)
    normals[x == 0] = (0.0, 0.0, -1.0)
    edge_i, edge_j = np.arange(8), np.arange(1, 9)
    return centroids, normals, edge_i, edge_j


def test_a_valley_is_concave_and_a_ridge_is_not():
    bend = np.radians(20)
    valley = concave_edges(*_fold(+1.0), bend)
    ridge = concave_edges(*_fold(-1.0), bend)
    assert valley[[3, 4]].all() and not valley[[0, 1, 6, 7]].any()  # only across the fold, where normals turn
    assert not ridge.any()


def test_a_fold_under_the_bend_is_not_a_crease():
    assert not concave_edges(*_fold(+1.0), np.radians(60)).any()


def test_the_median_bend_is_the_typical_angle_between_neighbours():
    normals = np.array([[0, 0, -1], [0, np.sin(0.1), -np.cos(0.1)], [0, 0, -1.0], [0, 0, -1.0]])
    assert np.isclose(median_bend(normals, np.array([0, 0, 2]), np.array([1, 2, 3])), 0.0)
    assert np.isclose(median_bend(normals, np.array([0, 1]), np.array([1, 2])), 0.1)


def test_crease_voxels_grow_back_ring_by_ring_from_the_parts_they_touch():
    # A chain 0-1-2-3-4-5-6: parts 0 (voxels 0, 1) and 1 (voxels 5, 6), a crease between them.
    clusters = np.array([0, 0, -1, -1, -1, 1, 1])
    open_ = clusters < 0
    edge_i, edge_j = np.arange(6), np.arange(1, 7)
    grown = grow_into(clusters, edge_i, edge_j, open_)
    assert grown[[0, 1, 2]].tolist() == [0, 0, 0] and grown[[4, 5, 6]].tolist() == [1, 1, 1]
    assert grown[3] in (0, 1)
    island = grow_into(np.array([0, -1, -1]), np.array([0]), np.array([1]), np.array([False, True, True]))
    assert island.tolist() == [0, 0, -1]  # no edge reaches voxel 2


def test_parts_stay_apart_only_where_most_of_their_contact_is_a_crease():
    parts = np.array([0, 0, 1, 1, 2, 2])
    edge_i = np.array([1, 1, 0, 3, 3, 2])
    edge_j = np.array([2, 3, 3, 4, 5, 5])
    concave = np.array([True, True, False, False, True, False])  # 0-1: 2 of 3; 1-2: 1 of 3
    joined = join_unless_concave(parts, edge_i, edge_j, concave)
    assert joined[2] == joined[4] != joined[0]
    assert join_unless_concave(np.array([-1, 0, 1]), np.array([0, 1]), np.array([1, 2]),
                               np.array([False, False])).tolist() == [-1, 0, 0]
