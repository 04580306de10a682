"""Plane and cylinder geometry, boxes and segmentation scores."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from psorr.decomposition.preprocess import smallest_eigenpairs, voxel_downsample
from psorr.geometry import shapes
from psorr.geometry.boxes import box_around_axis
from psorr.synthetic.metrics import segmentation_scores
from psorr.types import PrimitiveKind


def _cylinder_points(rng, centre, axis, radius, n=400, arc=np.pi, noise=0.0):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    u = np.cross(axis, [1, 0, 0] if abs(axis[0]) < 0.9 else [0, 1, 0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    theta = rng.uniform(0, arc, n)
    h = rng.uniform(-0.05, 0.05, n)
    normals = np.outer(np.cos(theta), u) + np.outer(np.sin(theta), v)
    points = np.asarray(centre) + radius * normals + np.outer(h, axis) + rng.normal(0, noise, (n, 3))
    return points, normals


@settings(max_examples=30, deadline=None)
@given(st.floats(0.01, 0.2), st.integers(0, 10_000))
def test_cylinder_from_two_oriented_points_is_exact(radius, seed):
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    points, normals = _cylinder_points(rng, [0.1, -0.2, 1.0], axis, radius, n=2)
    params, kept = shapes.cylinders_from_point_pairs(points[:1], normals[:1], points[1:], normals[1:])
    if len(kept) == 0:  # near-parallel normals say nothing about the axis
        return
    assert params[0, 6] == pytest.approx(radius, rel=1e-6)
    assert abs(params[0, 3:6] @ (axis / np.linalg.norm(axis))) == pytest.approx(1.0, abs=1e-9)
    assert shapes.distances(PrimitiveKind.CYLINDER, params[0], points).max() < 1e-9


def test_cylinder_fit_recovers_a_short_noisy_arc():
    rng = np.random.default_rng(3)
    points, normals = _cylinder_points(rng, [0, 0, 0.8], [0.2, 0.9, 0.1], 0.03, arc=1.4, noise=0.001)
    noisy_normals = normals + rng.normal(0, 0.05, normals.shape)
    params = shapes.fit(PrimitiveKind.CYLINDER, points, noisy_normals, refine=True)
    assert params[6] == pytest.approx(0.03, rel=0.05)
    assert shapes.fit(PrimitiveKind.CYLINDER, points, normals, max_radius=0.01) is None


def test_plane_fit_faces_the_sensor():
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-1, 1, (200, 2)), np.full(200, 1.5)])
    n0, n1, n2, d = shapes.fit_plane(pts)
    assert (n0, n1, n2) == pytest.approx((0, 0, -1)) and d == pytest.approx(1.5)


def test_closed_form_eigenvectors_match_lapack():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(500, 12, 3)) * [1.0, 0.5, 0.01]
    cov = np.einsum("nki,nkj->nij", x, x)
    lam, vec = smallest_eigenpairs(cov)
    ref_lam, ref_vec = np.linalg.eigh(cov)
    assert np.allclose(lam, ref_lam[:, 0], atol=1e-10)
    assert np.allclose(np.abs(np.einsum("ij,ij->i", vec, ref_vec[:, :, 0])), 1.0, atol=1e-8)


def test_voxel_map_back_covers_every_point():
    rng = np.random.default_rng(2)
    pts = rng.uniform(0, 0.3, (5000, 3))
    centroids, voxel_of = voxel_downsample(pts, 0.05)
    assert voxel_of.min() == 0 and voxel_of.max() == len(centroids) - 1
    assert np.allclose(centroids[voxel_of[:10]], [pts[voxel_of == v].mean(0) for v in voxel_of[:10]])


def test_box_is_minimal_for_a_rotated_rectangle():
    rng = np.random.default_rng(4)
    local = np.column_stack([rng.uniform(-0.1, 0.1, 3000), rng.uniform(-0.03, 0.03, 3000), np.zeros(3000)])
    c, s = np.cos(0.4), np.sin(0.4)
    pts = local @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + [1, 2, 3]
    box = box_around_axis(pts, [0, 0, 1])
    assert sorted(box.extent[:2]) == pytest.approx([0.06, 0.2], abs=0.002)
    assert box.volume == pytest.approx(0.0, abs=1e-12)


def test_segmentation_scores_by_hand():
    truth = np.array([1, 1, 1, 1, 2, 2, 2, 2, 3, 3])  # 1 is the table
    labels = np.array([0, 0, 0, 1, 1, 1, 1, -1, 2, 2])
    scores = segmentation_scores(truth, labels, background=(1,))
    # Object 2: primitive 1 (majority 2, 3 of 4 points) covers 3/4; object 3: 2/2.
    assert scores.coverage == pytest.approx((0.75 + 1.0) / 2)
    assert scores.purity == pytest.approx((3 + 2) / (4 + 2))


def test_the_cylinder_fit_jacobian_is_the_residuals_derivative():
    # refine_cylinder's least squares takes its Jacobian from _CylinderFit.jacobian: check it against
    # central differences at a start off the truth, on a noisy arc.
    rng = np.random.default_rng(5)
    axis = np.array([0.2, 0.1, 1.0]) / np.linalg.norm([0.2, 0.1, 1.0])
    u, v = shapes.orthonormal_frame(axis)
    t, h = rng.uniform(0, 1.5, 500), rng.uniform(-0.05, 0.05, 500)
    points = (np.array([0.1, 0.0, 0.8]) + 0.03 * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)
              + h[:, None] * axis + rng.normal(0, 0.001, (500, 3)))
    fit = shapes._CylinderFit(points, np.array([0.102, 0.001, 0.8, 0.18, 0.1, 0.98, 0.028]))
    x = np.array([0.01, -0.02, 0.003, -0.001, 0.029])
    step = 1e-7
    numeric = np.column_stack([(fit.residuals(x + step * e) - fit.residuals(x - step * e)) / (2 * step)
                               for e in np.eye(5)])
    assert np.allclose(fit.jacobian(x), numeric, atol=1e-6)


def test_refining_a_cylinder_removes_the_bias_of_a_short_noisy_arc():
    rng = np.random.default_rng(6)
    axis = np.array([0.0, 0.3, 1.0]) / np.linalg.norm([0.0, 0.3, 1.0])
    u, v = shapes.orthonormal_frame(axis)
    t, h = rng.uniform(0, 1.2, 3000), rng.uniform(-0.04, 0.04, 3000)
    radial = np.cos(t)[:, None] * u + np.sin(t)[:, None] * v
    points = np.array([0.0, 0.1, 0.9]) + 0.025 * radial + h[:, None] * axis + rng.normal(0, 0.0015, (3000, 3))
    rough = shapes.fit_cylinder(points, radial)
    refined = shapes.refine_cylinder(points, rough)
    assert abs(refined[6] - 0.025) < abs(rough[6] - 0.025) and abs(refined[6] - 0.025) < 0.001
    assert abs(np.dot(refined[3:6], axis)) > 0.999
