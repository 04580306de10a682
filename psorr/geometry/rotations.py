"""Rotations as 3x3 matrices and rotation vectors, in numpy.

scipy's Rotation costs 0.1-0.2 ms a conversion (scipy 1.17), and the damped ICP converts twice an
iteration: over the peers benchmark's scenes that was 4-5% of recognition's CPU time.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

_NEAR_HALF_TURN = np.pi - 1e-3  # rad: from here on the skew part no longer fixes the axis well


def cross(a, b) -> np.ndarray:
    """a x b, term for term as np.cross computes it (so the same bits), without its 50 microseconds of axis
    handling: of two 3-vectors given as sequences of floats, or of many at once given as their components
    (3, N), giving (3, N)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def turn(axis: np.ndarray, angle: float) -> np.ndarray:
    """(3, 3) rotation by ``angle`` radians about the unit ``axis`` (3,) (Rodrigues)."""
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def turn_about_line(axis: np.ndarray, angle: float, point: np.ndarray) -> np.ndarray:
    """(4, 4) rotation by ``angle`` radians about the line through ``point`` (3,) along the unit ``axis`` (3,)."""
    S = np.eye(4)
    S[:3, :3] = turn(axis, angle)
    S[:3, 3] = point - S[:3, :3] @ point
    return S


def from_rotation_vector(rotvec: np.ndarray) -> np.ndarray:
    """(3, 3) rotation of the rotation vector ``rotvec`` (3,): axis times angle in radians."""
    angle = float(np.linalg.norm(rotvec))
    if angle < 1e-12:
        return np.eye(3)
    return turn(rotvec / angle, angle)


def rotation_angle(R: np.ndarray) -> float:
    """The angle (radians, in [0, pi]) of the rotation ``R`` (3, 3)."""
    return float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))


def rotation_vector(R: np.ndarray) -> np.ndarray:
    """(3,) rotation vector (axis times angle in radians, angle in [0, pi]) of the rotation ``R`` (3, 3)."""
    angle = rotation_angle(R)
    skew = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle < 1e-6:
        return skew / 2.0  # sin(angle) ~ angle: the skew part is 2 x the rotation vector
    if angle > _NEAR_HALF_TURN:
        return Rotation.from_matrix(R).as_rotvec()
    return skew * (angle / (2.0 * np.sin(angle)))


def kabsch_rotations(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The rotations R (K, 3, 3) that carry the directions ``source`` (K, N, 3) closest onto ``target``
    (K, N, 3), set by set, in least squares (Kabsch; no reflection)."""
    U, _, Vt = np.linalg.svd(np.einsum("kij,kil->kjl", source, target))
    D = np.repeat(np.eye(3)[None], len(U), axis=0)
    D[:, 2, 2] = np.sign(np.linalg.det(np.einsum("kji,klj->kil", Vt, U)))
    return np.einsum("kji,kjl,kml->kim", Vt, D, U)
