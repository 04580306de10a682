"""Tests for psorr.geometry.box_overlap: rigid moves and the exact box-box intersection volume. Separating axes and
properties over random boxes: test_box_overlap_sat.py."""

from __future__ import annotations

import numpy as np
import pytest
from oriented_boxes import box, random_box
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection
from scipy.spatial.transform import Rotation

from psorr.errors import InvalidInputError, PsorrError
from psorr.geometry.box_overlap import (
    boxes_may_overlap,
    intersection_points,
    intersection_ratio,
    intersection_volume,
    transform_box,
)
from psorr.types import OrientedBox

SQRT_HALF = np.sqrt(0.5)


def rigid(rng) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    T[:3, 3] = rng.uniform(-2, 2, 3)
    return T


def inside(b: OrientedBox, points: np.ndarray, slack: float = 0.0) -> np.ndarray:
    return (np.abs((points - b.center) @ b.rotation) <= b.extent / 2 + slack).all(axis=1)


def reference_polytope(a: OrientedBox, b: OrientedBox) -> np.ndarray | None:
    """Vertices (V, 3) of the intersection from the 12 half-spaces (independent of the edge clipping), or None."""
    rows = []
    for bx in (a, b):
        for k in range(3):
            n, h = bx.rotation[:, k], bx.extent[k] / 2
            rows += [np.r_[n, -n @ bx.center - h], np.r_[-n, n @ bx.center - h]]
    H = np.array(rows)
    # Chebyshev centre: the deepest interior point, needed by HalfspaceIntersection.
    res = linprog([0, 0, 0, -1], A_ub=np.c_[H[:, :3], np.ones(len(H))], b_ub=-H[:, 3],
                  bounds=[(None, None)] * 3 + [(0, None)])
    if res.status != 0 or res.x[3] < 1e-7:
        return None
    return HalfspaceIntersection(H, res.x[:3]).intersections


def monte_carlo_volume(a: OrientedBox, b: OrientedBox, n: int, rng) -> float:
    samples = a.center + (rng.uniform(-0.5, 0.5, (n, 3)) * a.extent) @ a.rotation.T
    return a.volume * float(inside(b, samples).mean())


# --- transform_box -------------------------------------------------------------------------------------------------


def test_transform_box_moves_corners_rigidly():
    rng = np.random.default_rng(0)
    b, T = random_box(rng), rigid(rng)
    moved = transform_box(b, T)
    np.testing.assert_allclose(moved.corners(), b.corners() @ T[:3, :3].T + T[:3, 3], atol=1e-12)
    np.testing.assert_array_equal(moved.extent, b.extent)


@pytest.mark.parametrize("T", [np.diag([2.0, 1, 1, 1]), np.diag([-1.0, 1, 1, 1]), np.eye(3), np.full((4, 4), np.nan)])
def test_transform_box_rejects_non_rigid(T):
    with pytest.raises(InvalidInputError):
        transform_box(box(), T)


def test_volume_is_invariant_under_a_common_rigid_motion():
    rng = np.random.default_rng(1)
    for _ in range(20):
        a, b, T = random_box(rng), random_box(rng), rigid(rng)
        assert intersection_volume(transform_box(a, T), transform_box(b, T)) == pytest.approx(
            intersection_volume(a, b), rel=1e-9, abs=1e-13)


# --- simple cases --------------------------------------------------------------------------------------------------


def test_identical_boxes():
    rng = np.random.default_rng(2)
    for _ in range(10):
        b = random_box(rng)
        assert intersection_volume(b, b) == pytest.approx(b.volume, rel=1e-12)
        assert intersection_ratio(b, b) == pytest.approx(1.0)
        assert boxes_may_overlap(b, b)


def test_disjoint_boxes():
    a = box((0, 0, 0), (1, 2, 3))
    b = box((3, 0, 0), (1, 1, 1), Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_matrix())
    assert not boxes_may_overlap(a, b)
    assert intersection_volume(a, b) == 0.0
    assert intersection_ratio(a, b) == 0.0
    assert len(intersection_points(a, b)) == 0


def test_box_inside_another_gives_its_own_volume():
    rng = np.random.default_rng(3)
    for _ in range(20):
        big = random_box(rng)
        small = box(big.center + rng.uniform(-0.01, 0.01, 3), np.full(3, big.extent.min() / 4),
                    Rotation.random(random_state=rng).as_matrix())
        assert intersection_volume(big, small) == pytest.approx(small.volume, rel=1e-12)
        assert intersection_volume(small, big) == pytest.approx(small.volume, rel=1e-12)
        assert intersection_ratio(small, big, min_thickness=0.0) == pytest.approx(1.0)
        assert intersection_ratio(big, small, min_thickness=0.0) == pytest.approx(small.volume / big.volume)


def test_axis_aligned_boxes_match_the_product_of_overlaps():
    rng = np.random.default_rng(4)
    for i in range(50):
        ca, cb = rng.uniform(-0.5, 0.5, (2, 3))
        ea, eb = rng.uniform(0.1, 1.0, (2, 3))
        overlap = np.clip(np.minimum(ca + ea / 2, cb + eb / 2) - np.maximum(ca - ea / 2, cb - eb / 2), 0, None)
        a, b = box(ca, ea), box(cb, eb)
        if i % 2:  # the same, turned together: still axis-aligned to each other
            T = rigid(rng)
            a, b = transform_box(a, T), transform_box(b, T)
        assert intersection_volume(a, b) == pytest.approx(np.prod(overlap), rel=1e-9, abs=1e-14)


# --- exactness -----------------------------------------------------------------------------------------------------


def test_hull_points_are_exactly_the_intersection_polytope_vertices():
    # The polytope's vertices each lie on 3 face planes; the box owning 2 or 3 of them
    # contributes an edge crossing the other's face, or a vertex inside the other.
    # So the clipped-edge points must include every vertex found independently from the
    # 12 half-spaces, and must themselves all lie in both boxes.
    rng = np.random.default_rng(5)
    checked = 0
    for _ in range(100):
        a, b = random_box(rng), random_box(rng)
        vertices = reference_polytope(a, b)
        points = intersection_points(a, b)
        if vertices is None:
            assert intersection_volume(a, b) < 1e-12
            continue
        checked += 1
        assert inside(a, points, 1e-9).all() and inside(b, points, 1e-9).all()
        gap = np.linalg.norm(vertices[:, None, :] - points[None, :, :], axis=2).min(axis=1)
        assert gap.max() < 1e-7
        assert intersection_volume(a, b) == pytest.approx(ConvexHull(vertices).volume, rel=1e-6, abs=1e-13)
    assert checked > 50


def test_random_rotated_boxes_match_monte_carlo():
    rng = np.random.default_rng(6)
    mc_rng = np.random.default_rng(7)
    compared = 0
    while compared < 20:
        a, b = random_box(rng, spread=0.15, size=(0.1, 1.0)), random_box(rng, spread=0.15, size=(0.1, 1.0))
        if a.volume > b.volume:
            a, b = b, a  # sample in the smaller box: larger hit rate, smaller relative error
        exact = intersection_volume(a, b)
        if exact < 0.1 * a.volume:
            continue  # a hit rate under 10% would put the 200k-sample noise near the 3% bound
        assert exact == pytest.approx(monte_carlo_volume(a, b, 200_000, mc_rng), rel=0.03)
        compared += 1


def test_edge_into_face_is_a_triangular_prism():
    # B, turned 45 degrees about z, pushes a vertical edge depth d into A's +x face.
    turned_z = Rotation.from_euler("z", 45, degrees=True).as_matrix()
    a = box()
    for depth in (0.2, 0.05, 1e-3):
        b = box((0.5 + SQRT_HALF - depth, 0, 0), (1, 1, 1), turned_z)
        assert intersection_volume(a, b) == pytest.approx(depth**2, rel=1e-9)
        assert intersection_volume(b, a) == pytest.approx(depth**2, rel=1e-9)


def test_edge_on_edge():
    # A's vertical edge (A turned 45 about z) meets B's horizontal edge (B turned 45 about y)
    # at right angles; pushed together by d, the intersection is
    # integral_0^d 4 s (d - s) ds = 2 d^3 / 3.
    a = box(rotation=Rotation.from_euler("z", 45, degrees=True).as_matrix())
    turned_y = Rotation.from_euler("y", 45, degrees=True).as_matrix()
    for depth in (0.3, 0.1, 0.01):
        b = box((2 * SQRT_HALF - depth, 0, 0), rotation=turned_y)
        assert boxes_may_overlap(a, b)
        assert intersection_volume(a, b) == pytest.approx(2 * depth**3 / 3, rel=1e-9)
    touching = box((2 * SQRT_HALF, 0, 0), rotation=turned_y)
    assert boxes_may_overlap(a, touching)  # the edges meet in a point
    assert intersection_volume(a, touching) < 1e-15
    apart = box((2 * SQRT_HALF + 1e-6, 0, 0), rotation=turned_y)
    assert not boxes_may_overlap(a, apart)  # only a cross-product axis separates these
    assert intersection_volume(a, apart) == 0.0


def test_face_touching_boxes_have_zero_volume():
    rng = np.random.default_rng(8)
    a = box((0, 0, 0), (1, 1, 1))
    for shift in ((1, 0.3, 0.2), (0.2, -1, 0.4), (0, 0, 1)):
        b = box(shift, (1, 1, 1))
        assert boxes_may_overlap(a, b)
        assert intersection_volume(a, b) == 0.0
        T = rigid(rng)
        assert intersection_volume(transform_box(a, T), transform_box(b, T)) < 1e-12
        apart = box(np.asarray(shift, float) * (1 + 1e-6), (1, 1, 1))
        assert not boxes_may_overlap(a, apart)
        assert intersection_volume(a, apart) == 0.0
    corner = box((1, 1, 1), (1, 1, 1))
    assert boxes_may_overlap(a, corner) and intersection_volume(a, corner) == 0.0


# --- flat boxes and the ratio --------------------------------------------------------------------------------------


def test_flat_boxes_volume_and_thickened_ratio():
    rng = np.random.default_rng(9)
    T = rigid(rng)
    plate = box((0, 0, 0), (1.0, 0.5, 0.001))
    moved = transform_box(plate, T)
    assert intersection_volume(moved, moved) == pytest.approx(5e-4, rel=1e-9)
    assert intersection_ratio(moved, moved) == pytest.approx(1.0)
    # 2 mm apart along the normal: disjoint as they are, 3/5 overlapping once 5 mm thick.
    lifted = transform_box(box((0, 0, 0.002), (1.0, 0.5, 0.001)), T)
    assert intersection_volume(moved, lifted) == 0.0
    assert intersection_ratio(moved, lifted, min_thickness=0.0) == 0.0
    assert intersection_ratio(moved, lifted) == pytest.approx(0.6, rel=1e-9)
    # Half of the plate slid off in-plane, 0.5 mm off the plane: half the area, unchanged by thickening.
    slid = transform_box(box((0.5, 0, 0.0005), (1.0, 0.5, 0.001)), T)
    assert intersection_ratio(moved, slid) == pytest.approx(0.5 * 4.5 / 5, rel=1e-9)
    assert intersection_ratio(moved, slid, min_thickness=0.0) == pytest.approx(0.25, rel=1e-9)


def test_crossing_plates_and_zero_thickness():
    rng = np.random.default_rng(10)
    T = rigid(rng)
    floor = transform_box(box((0, 0, 0), (1, 1, 0.001)), T)
    wall = transform_box(box((0, 0, 0), (1, 0.001, 1)), T)
    # They share a 1 m x 1 mm x 1 mm bar.
    assert intersection_volume(floor, wall) == pytest.approx(1e-6, rel=1e-6)
    assert intersection_volume(wall, floor) == pytest.approx(1e-6, rel=1e-6)
    sheet = transform_box(box((0, 0, 0), (1, 1, 0.0)), T)
    assert intersection_volume(sheet, floor) == 0.0
    assert intersection_volume(sheet, sheet) == 0.0
    assert intersection_ratio(sheet, sheet) == pytest.approx(1.0)
    assert intersection_ratio(sheet, floor) == pytest.approx(1.0)  # both become 5 mm slabs
    assert intersection_ratio(sheet, sheet, min_thickness=0.0) == 0.0


def test_flat_random_boxes_match_the_half_space_reference():
    rng = np.random.default_rng(11)
    checked = 0
    for _ in range(60):
        a = random_box(rng, spread=0.2, size=(0.2, 1.0))
        b = random_box(rng, spread=0.2, size=(0.2, 1.0))
        a = box(a.center, np.r_[a.extent[:2], 0.001], a.rotation)
        vertices = reference_polytope(a, b)
        if vertices is None:
            continue
        checked += 1
        assert intersection_volume(a, b) == pytest.approx(ConvexHull(vertices).volume, rel=1e-6)
    assert checked > 10


def test_ratio_is_in_unit_interval_and_validates():
    rng = np.random.default_rng(12)
    for _ in range(50):
        r = intersection_ratio(random_box(rng), random_box(rng))
        assert 0.0 <= r <= 1.0
    for bad in (-0.001, np.nan, np.inf):
        with pytest.raises(InvalidInputError):
            intersection_ratio(box(), box(), min_thickness=bad)


@pytest.mark.parametrize("bad", [box(extent=(-1, 1, 1)), box(center=(np.nan, 0, 0)), box(extent=(np.inf, 1, 1))])
def test_bad_boxes_raise_psorr_errors(bad):
    for call in (intersection_volume, intersection_points, intersection_ratio):
        with pytest.raises(PsorrError):
            call(bad, box())
        with pytest.raises(PsorrError):
            call(box(), bad)
