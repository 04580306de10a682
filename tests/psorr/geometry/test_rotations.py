"""psorr.geometry.rotations: numpy conversions between rotation matrices and rotation vectors, and the cross product."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from psorr.geometry.rotations import cross, from_rotation_vector, rotation_vector, turn


@pytest.mark.parametrize("scale", [0.0, 1e-9, 1e-5, 0.3, 2.0, np.pi - 2e-3, np.pi - 1e-4, np.pi])
def test_conversions_agree_with_scipy_from_no_turn_to_a_half_turn(scale):
    rng = np.random.default_rng(0)
    for _ in range(50):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        rotvec = axis * scale
        R = Rotation.from_rotvec(rotvec).as_matrix()
        np.testing.assert_allclose(from_rotation_vector(rotvec), R, atol=1e-12)
        # At a half turn, v and -v are the same rotation: compare the rotations they give.
        np.testing.assert_allclose(Rotation.from_rotvec(rotation_vector(R)).as_matrix(), R, atol=1e-9)
        if scale < np.pi - 1e-3:
            np.testing.assert_allclose(rotation_vector(R), rotvec, atol=1e-9)


def test_a_quarter_turn_about_z_takes_x_to_y():
    np.testing.assert_allclose(turn(np.array([0.0, 0.0, 1.0]), np.pi / 2) @ [1.0, 0, 0], [0, 1.0, 0], atol=1e-15)


def test_cross_is_np_cross_to_the_bit():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    assert np.array_equal(cross(a.T, b.T).T, np.cross(a, b))
    assert np.array_equal(cross(a[0].tolist(), b[0].tolist()), np.cross(a[0], b[0]))
