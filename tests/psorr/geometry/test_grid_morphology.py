import numpy as np
import pytest
from scipy import ndimage

from psorr.geometry.grid_morphology import closing, dilate, erode, opening


def _masks():
    rng = np.random.default_rng(7)
    for _ in range(60):
        shape = (int(rng.integers(1, 40)), int(rng.integers(1, 40)))
        yield rng.random(shape) < rng.uniform(0.02, 0.7)


@pytest.mark.parametrize("iterations", [1, 2, 3])
def test_each_operation_equals_scipys_with_its_default_cross_and_border(iterations):
    for mask in _masks():
        assert (dilate(mask, iterations) == ndimage.binary_dilation(mask, iterations=iterations)).all()
        assert (erode(mask, iterations) == ndimage.binary_erosion(mask, iterations=iterations)).all()
        assert (closing(mask, iterations) == ndimage.binary_closing(mask, iterations=iterations)).all()
        assert (opening(mask, iterations) == ndimage.binary_opening(mask, iterations=iterations)).all()


def test_a_lone_cell_grows_into_a_cross_and_a_cross_erodes_back_to_its_centre():
    mask = np.zeros((5, 5), dtype=bool)
    mask[2, 2] = True
    cross = dilate(mask)
    assert cross.sum() == 5 and cross[1, 2] and cross[2, 1] and not cross[1, 1]
    assert (erode(cross) == mask).all()
    assert not opening(mask).any()


def test_the_input_is_left_as_it_was():
    mask = np.eye(6, dtype=bool)
    before = mask.copy()
    closing(mask, 2), opening(mask, 2)
    assert (mask == before).all()
