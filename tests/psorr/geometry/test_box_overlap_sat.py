"""Tests for psorr.geometry.box_overlap's separating-axis test (overlap_candidates, boxes_may_overlap) and properties
of the exact volume that hold for any two boxes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from oriented_boxes import box, random_box
from scipy.spatial.transform import Rotation

from psorr.errors import InvalidInputError
from psorr.geometry.box_overlap import boxes_may_overlap, boxes_to_arrays, intersection_volume, overlap_candidates

# --- separating axes -----------------------------------------------------------------------------------------------


def test_vectorised_candidates_agree_with_scalar_sat():
    rng = np.random.default_rng(13)
    set_a = [random_box(rng, spread=1.0) for _ in range(20)]
    set_b = [random_box(rng, spread=1.0) for _ in range(10)]
    grid = overlap_candidates(*boxes_to_arrays(set_a), *boxes_to_arrays(set_b))
    assert grid.shape == (20, 10) and grid.dtype == bool
    scalar = np.array([[boxes_may_overlap(a, b) for b in set_b] for a in set_a])
    np.testing.assert_array_equal(grid, scalar)
    assert 0 < grid.sum() < grid.size
    # SAT never rejects a pair with a positive intersection.
    volumes = np.array([[intersection_volume(a, b) for b in set_b] for a in set_a])
    assert not (volumes > 0)[~grid].any()
    # A mask restricts the test to its pairs and leaves the rest False.
    mask = rng.random(grid.shape) < 0.5
    masked = overlap_candidates(*boxes_to_arrays(set_a), *boxes_to_arrays(set_b), mask=mask)
    np.testing.assert_array_equal(masked, grid & mask)


def test_overlap_candidates_shapes():
    empty = boxes_to_arrays([])
    one = boxes_to_arrays([box()])
    assert overlap_candidates(*empty, *one).shape == (0, 1)
    assert overlap_candidates(*one, *empty).shape == (1, 0)
    assert overlap_candidates(*one, *one).tolist() == [[True]]
    with pytest.raises(InvalidInputError):
        overlap_candidates(np.zeros((2, 3)), np.zeros((1, 3, 3)), np.zeros((2, 3)), *one)
    with pytest.raises(InvalidInputError, match="mask must be"):
        overlap_candidates(*one, *one, mask=np.ones((2, 1), dtype=bool))


# --- properties ----------------------------------------------------------------------------------------------------

coordinate = st.floats(-1.0, 1.0, allow_nan=False)
boxes = st.builds(
    lambda c, e, q: box(c, e, Rotation.from_quat(q).as_matrix()),
    st.tuples(coordinate, coordinate, coordinate),
    st.tuples(*[st.floats(1e-3, 1.0)] * 3),
    st.tuples(*[coordinate] * 4).filter(lambda q: np.linalg.norm(q) > 0.1),
)


@settings(max_examples=300, deadline=None)
@given(boxes, boxes)
def test_volume_is_symmetric_and_bounded(a, b):
    forward, backward = intersection_volume(a, b), intersection_volume(b, a)
    assert forward == pytest.approx(backward, rel=1e-7, abs=1e-12)
    assert 0.0 <= forward <= min(a.volume, b.volume)
    if not boxes_may_overlap(a, b):
        assert forward == 0.0
