"""Tests for psorr.geometry.box_batch: batched exact box intersection ratios, checked against box_overlap pair by
pair."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from psorr.errors import InvalidInputError
from psorr.geometry.box_batch import intersection_ratios
from psorr.geometry.box_overlap import intersection_ratio
from psorr.types import OrientedBox

SQRT_HALF = np.sqrt(0.5)
NAMES = ("centers_a", "rotations_a", "extents_a", "centers_b", "rotations_b", "extents_b")


def reference(arrays, min_thickness) -> np.ndarray:
    ca, Ra, ea, cb, Rb, eb = arrays
    return np.array([intersection_ratio(OrientedBox(ca[i], Ra[i], ea[i]), OrientedBox(cb[i], Rb[i], eb[i]),
                                        min_thickness) for i in range(len(ca))])


def pairs(*rows):
    """Stack rows of (center_a, rotation_a, extent_a, center_b, rotation_b, extent_b) into the six arrays."""
    eye = np.eye(3)
    return [np.array([np.asarray(eye if x is None else x, float) for x in column]) for column in zip(*rows)]


def moved(arrays, rng):
    """The same pairs under one random rigid motion per row."""
    ca, Ra, ea, cb, Rb, eb = arrays
    R = Rotation.random(len(ca), random_state=rng).as_matrix()
    T = rng.uniform(-2, 2, (len(ca), 3))
    return [(R @ ca[..., None])[..., 0] + T, R @ Ra, ea, (R @ cb[..., None])[..., 0] + T, R @ Rb, eb]


def signed_permutations(rng, n) -> np.ndarray:
    """(n, 3, 3) random rotations by multiples of 90 degrees: the axes of one box along the other's."""
    out = np.zeros((n, 3, 3))
    for i in range(n):
        out[i, np.arange(3), rng.permutation(3)] = rng.choice([-1.0, 1.0], 3)
        if np.linalg.det(out[i]) < 0:
            out[i, 0] *= -1
    return out


def random_pairs(rng, n):
    """n pairs mixing partial overlaps, disjoint, nested, flush and touching boxes, and equal or 90-degree turned
    rotations; extents 1 mm to 20 cm (a third of the boxes flat), centres up to ~2 m from the origin."""
    kind = np.arange(n) % 6
    Ra = Rotation.random(n, random_state=rng).as_matrix()
    Rb = Rotation.random(n, random_state=rng).as_matrix()
    ea = np.exp(rng.uniform(np.log(1e-3), np.log(0.2), (n, 3)))
    eb = np.exp(rng.uniform(np.log(1e-3), np.log(0.2), (n, 3)))
    for e in (ea, eb):
        flat = rng.random(n) < 1 / 3
        e[flat, rng.integers(0, 3, flat.sum())] = rng.uniform(1e-3, 2e-3, flat.sum())
    ca = rng.uniform(-1.0, 1.0, (n, 3)) + [0.0, 0.0, 1.0]
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    reach = (np.linalg.norm(ea, axis=1) + np.linalg.norm(eb, axis=1)) / 2
    cb = ca + direction * (reach * rng.uniform(0.0, 1.1, n))[:, None]  # kinds 0, 1: mostly partial, some apart
    # Kinds 2 and 5: B turned like A or by 90 degrees from it, random offsets; kinds 3, 4 flush, touching or nested.
    turned = np.isin(kind, (2, 3, 4, 5))
    Rb[turned] = Ra[turned] @ np.where((kind[turned] == 5)[:, None, None] | (rng.random((turned.sum(), 1, 1)) < 0.5),
                                       signed_permutations(rng, turned.sum()), np.eye(3))
    hb_in_a = (np.abs(np.swapaxes(Ra, 1, 2) @ Rb) @ eb[..., None])[..., 0] / 2
    ha = ea / 2
    shift = rng.uniform(-1, 1, (n, 3)) * (ha + hb_in_a)
    axis, side = rng.integers(0, 3, n), rng.choice([-1.0, 1.0], n)
    rows = np.arange(n)
    # Kind 3: B's face on A's face plane, from inside (flush) or outside (touching); kind 4: B inside A.
    flush = rng.random(n) < 0.5
    ha_k, hb_k = ha[rows, axis], hb_in_a[rows, axis]
    shift[rows, axis] = side * np.where(flush, ha_k - hb_k, ha_k + hb_k)
    nested = kind == 4
    eb[nested] = ea[nested].min(1, keepdims=True) * rng.uniform(0.1, 0.6, (nested.sum(), 3))
    shift[nested] = rng.uniform(-0.2, 0.2, (nested.sum(), 3)) * ea[nested].min(1, keepdims=True)
    offset = (Ra @ shift[..., None])[..., 0]
    cb[turned] = ca[turned] + offset[turned]
    # Half of the nested pairs the other way round: A inside B.
    swap = nested & (rng.random(n) < 0.5)
    ca[swap], cb[swap], Ra[swap], Rb[swap], ea[swap], eb[swap] = (
        cb[swap], ca[swap].copy(), Rb[swap], Ra[swap].copy(), eb[swap], ea[swap].copy())
    return [ca, Ra, ea, cb, Rb, eb], kind


@pytest.mark.parametrize("min_thickness", [0.0, 0.005, 0.04])
def test_matches_box_overlap_on_random_pairs(min_thickness):
    arrays, kind = random_pairs(np.random.default_rng(20), 2400)
    batch = intersection_ratios(*arrays, min_thickness=min_thickness)
    expected = reference(arrays, min_thickness)
    assert batch.shape == (2400,) and batch.dtype == np.float64
    np.testing.assert_allclose(batch, expected, rtol=0, atol=1e-7)
    assert ((batch > 0) & (batch < 1)).sum() > 600  # many partial overlaps
    if min_thickness == 0.0:  # (thickening turns most touching pairs into overlapping ones)
        assert (batch == 0).sum() > 300 and (batch == 1).sum() > 150  # disjoint or touching; A nested in B
        touching = (kind == 3) & (expected == 0)
        assert touching.sum() > 50 and (batch[touching] == 0).all()


def test_near_parallel_faces_match_box_overlap():
    # Flush boxes, then B turned by 1e-14 .. 1e-3 rad: faces that (nearly) share a plane and may cross.
    rng = np.random.default_rng(21)
    n = 400
    Ra = Rotation.random(n, random_state=rng).as_matrix()
    tilt = Rotation.from_rotvec(rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-14, -3, (n, 1))).as_matrix()
    ea, eb = rng.uniform(0.01, 0.2, (n, 3)), rng.uniform(0.01, 0.2, (n, 3))
    shift = rng.uniform(-0.5, 0.5, (n, 3)) * (ea + eb) / 2
    shift[:, 2] = (ea[:, 2] - eb[:, 2]) / 2  # top faces in one plane
    ca = rng.uniform(-1, 1, (n, 3))
    arrays = [ca, Ra, ea, ca + (Ra @ shift[..., None])[..., 0], Ra @ tilt, eb]
    np.testing.assert_allclose(intersection_ratios(*arrays, min_thickness=0.0), reference(arrays, 0.0),
                               rtol=0, atol=1e-7)


def test_invariant_under_a_common_rigid_motion_and_scale():
    # Tighter than the comparison with box_overlap, whose 1e-11 m slack moves its hull: here only rounding differs.
    arrays, _ = random_pairs(np.random.default_rng(24), 1200)
    ca, Ra, ea, cb, Rb, eb = moved(arrays, np.random.default_rng(25))
    for min_thickness in (0.0, 0.005):
        np.testing.assert_allclose(intersection_ratios(ca * 10, Ra, ea * 10, cb * 10, Rb, eb * 10, min_thickness * 10),
                                   intersection_ratios(*arrays, min_thickness=min_thickness), rtol=0, atol=1e-11)


# --- explicit cases ------------------------------------------------------------------------------------------------


def test_disjoint_touching_and_flat_boxes_give_zero():
    rng = np.random.default_rng(22)
    cube = ((0, 0, 0), None, (1, 1, 1))
    arrays = pairs(
        (*cube, (3, 0, 0), Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_matrix(), (1, 1, 1)),  # apart
        (*cube, (1, 0.3, 0.2), None, (1, 1, 1)),  # faces touching
        (*cube, (0.2, -1.5, 0.4), None, (1, 2, 1)),
        (*cube, (1, 1, 1), None, (1, 1, 1)),  # corners touching
        ((0, 0, 0), Rotation.from_euler("z", 45, degrees=True).as_matrix(), (1, 1, 1),  # edges crossing
         (2 * SQRT_HALF, 0, 0), Rotation.from_euler("y", 45, degrees=True).as_matrix(), (1, 1, 1)),
        (*cube, (0, 0, 0), None, (1, 1, 0)),  # a zero-thickness sheet
        ((0, 0, 0), None, (1, 1, 0), (0, 0, 0), None, (1, 1, 1)),
    )
    for case in (arrays, moved(arrays, rng)):
        np.testing.assert_array_equal(intersection_ratios(*case, min_thickness=0.0), 0.0)
    # Thickened to 5 mm, the sheets overlap the cube; the touching faces stay apart, only thicker.
    thick = intersection_ratios(*arrays, min_thickness=0.005)
    np.testing.assert_allclose(thick[-2:], [0.005, 1.0], rtol=1e-12)
    np.testing.assert_array_equal(thick[:5], 0.0)


def test_nested_boxes_give_the_smaller_volume():
    rng = np.random.default_rng(23)
    turned = Rotation.from_euler("xyz", [0.3, 0.2, 0.1]).as_matrix()
    arrays = pairs(
        ((0, 0, 0), None, (1, 2, 3), (0.1, 0.2, 0.3), turned, (0.2, 0.3, 0.4)),
        ((0.1, 0.2, 0.3), turned, (0.2, 0.3, 0.4), (0, 0, 0), None, (1, 2, 3)),
        ((0, 0, 0), None, (1, 2, 3), (0, 0, 0), None, (1, 2, 3)),  # identical
        ((0, 0, 0), None, (1, 2, 3), (0.25, 0, 0), None, (0.5, 2, 3)),  # flush with three faces
    )
    expected = [0.024 / 6, 1.0, 1.0, 0.5]
    for case in (arrays, moved(arrays, rng)):
        np.testing.assert_allclose(intersection_ratios(*case, min_thickness=0.0), expected, rtol=1e-12)


def test_exact_volumes_of_known_shapes():
    turned_z = Rotation.from_euler("z", 45, degrees=True).as_matrix()
    turned_y = Rotation.from_euler("y", 45, degrees=True).as_matrix()
    depths = np.array([0.2, 0.05, 1e-3])
    rows = [((0, 0, 0), None, (1, 1, 1), (0.5, 0.3, -0.2), None, (1, 1, 1))]  # boxes shifted: 0.5 * 0.7 * 0.8
    rows += [((0, 0, 0), None, (1, 1, 1), (0.5 + SQRT_HALF - d, 0, 0), turned_z, (1, 1, 1)) for d in depths]
    rows += [((0, 0, 0), turned_z, (1, 1, 1), (2 * SQRT_HALF - d, 0, 0), turned_y, (1, 1, 1)) for d in depths]
    # A triangular prism (an edge pushed into a face), and two edges crossing at right angles: 2 d^3 / 3.
    expected = np.r_[0.28, depths**2, 2 * depths**3 / 3]
    np.testing.assert_allclose(intersection_ratios(*pairs(*rows), min_thickness=0.0), expected, rtol=1e-9)


def test_empty_input():
    empty = [np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros((0, 3))] * 2
    result = intersection_ratios(*empty)
    assert result.shape == (0,) and result.dtype == np.float64


# --- errors --------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("which", range(6))
def test_non_finite_input_names_the_argument(which, bad):
    arrays = pairs(((0, 0, 0), None, (1, 1, 1), (0.5, 0, 0), None, (1, 1, 1)))
    arrays = [np.repeat(a, 3, axis=0) for a in arrays]
    arrays[which][1].flat[2] = bad
    with pytest.raises(InvalidInputError, match=NAMES[which]):
        intersection_ratios(*arrays)


@pytest.mark.parametrize("which", [2, 5])
def test_negative_extent_names_the_argument(which):
    arrays = pairs(((0, 0, 0), None, (1, 1, 1), (0.5, 0, 0), None, (1, 1, 1)))
    arrays[which][0, 1] = -0.1
    with pytest.raises(InvalidInputError, match=NAMES[which]):
        intersection_ratios(*arrays)


@pytest.mark.parametrize("which, shape", [(0, (2, 3)), (1, (1, 3)), (2, (1, 2)), (3, (3,)), (4, (1, 9)),
                                          (5, (1, 3, 1))])
def test_shape_mismatch_names_the_expected_shapes(which, shape):
    arrays = pairs(((0, 0, 0), None, (1, 1, 1), (0.5, 0, 0), None, (1, 1, 1)))
    arrays[which] = np.zeros(shape)
    with pytest.raises(InvalidInputError, match=r"centers \(N, 3\), rotations \(N, 3, 3\) and extents \(N, 3\)"):
        intersection_ratios(*arrays)


@pytest.mark.parametrize("bad", [-0.001, np.nan, np.inf])
def test_bad_min_thickness(bad):
    arrays = pairs(((0, 0, 0), None, (1, 1, 1), (0.5, 0, 0), None, (1, 1, 1)))
    with pytest.raises(InvalidInputError, match="min_thickness"):
        intersection_ratios(*arrays, min_thickness=bad)


def test_non_numeric_input():
    arrays = pairs(((0, 0, 0), None, (1, 1, 1), (0.5, 0, 0), None, (1, 1, 1)))
    arrays[0] = [["a", "b", "c"]]
    with pytest.raises(InvalidInputError, match="centers_a"):
        intersection_ratios(*arrays)
