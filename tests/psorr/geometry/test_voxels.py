"""Voxel means (psorr.geometry.voxels) and the supporting plane (psorr.geometry.support_plane)."""

import numpy as np
import open3d as o3d
import pytest

from psorr.errors import InvalidInputError
from psorr.geometry.support_plane import support_plane
from psorr.geometry.voxels import voxel_means


def _scattered(rng, n=20000):
    # A tilted table with a box on it, noisy: points that fall anywhere in their voxels.
    xy = rng.uniform(-0.4, 0.4, size=(n, 2))
    table = np.column_stack([xy, 0.9 + 0.2 * xy[:, 1] + rng.normal(0, 0.002, n)])
    box = rng.uniform([-0.05, -0.05, 0.8], [0.05, 0.05, 0.85], size=(n // 5, 3))
    return np.vstack([table, box])


def _sorted_rows(points):
    return points[np.lexsort(points.T[::-1])]


@pytest.mark.parametrize("voxel", [0.004, 0.011])
def test_voxel_means_are_open3ds_voxels(voxel):
    points = _scattered(np.random.default_rng(0))
    ours = voxel_means(points, voxel)
    theirs = np.asarray(o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points)).voxel_down_sample(voxel).points)
    assert ours.shape == theirs.shape
    np.testing.assert_allclose(_sorted_rows(ours), _sorted_rows(theirs), atol=1e-12)


def test_voxel_means_are_the_means_of_each_voxels_points():
    points = np.array([[0.0, 0.0, 0.0], [0.001, 0.0, 0.0], [0.0101, 0.0, 0.0], [0.0102, 0.0, 0.0015]])
    # The grid starts half a voxel below the least corner: the first two share a voxel, the last two another.
    np.testing.assert_allclose(voxel_means(points, 0.004), [[0.0005, 0.0, 0.0], [0.01015, 0.0, 0.00075]])


def test_voxel_means_do_not_depend_on_the_points_order():
    points = _scattered(np.random.default_rng(1))
    shuffled = points[np.random.default_rng(2).permutation(len(points))]
    np.testing.assert_allclose(voxel_means(points, 0.004), voxel_means(shuffled, 0.004), atol=1e-15)


def test_voxel_means_refuse_what_is_not_points():
    with pytest.raises(InvalidInputError, match=r"\(N, 3\)"):
        voxel_means(np.zeros((4, 2)), 0.004)
    with pytest.raises(InvalidInputError, match="voxel size"):
        voxel_means(np.zeros((4, 3)), 0.0)
    assert voxel_means(np.zeros((0, 3)), 0.004).shape == (0, 3)


def test_the_supporting_plane_is_the_least_squares_plane_of_its_inliers_in_any_order():
    points = _scattered(np.random.default_rng(3))
    found = support_plane(o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points)))
    again = support_plane(o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points[::-1].copy())))
    np.testing.assert_allclose(found.plane, again.plane, atol=1e-12)
    inliers = points[found.inliers]
    centre = inliers.mean(axis=0)
    normal = np.linalg.svd(inliers - centre, full_matrices=False)[2][-1]
    assert abs(abs(normal @ found.plane[:3]) - 1) < 1e-12
    assert abs(found.plane[:3] @ centre + found.plane[3]) < 1e-12
    assert found.plane[3] > 0  # the sensor, at the origin, on its positive side
    # The table's true normal is (0, -0.2, 1) normalised; the box's faces do not tilt it.
    assert np.degrees(np.arccos(abs(found.plane[:3] @ np.array([0, -0.2, 1]) / np.hypot(1, 0.2)))) < 0.2
