"""Colour segmentation (psorr.segment): boxes told apart by colour, the table left out, colour names."""

import numpy as np
import pytest
from coloured_scenes import BLUE, RED, stacked_boxes, two_boxes

from psorr import PointCloud
from psorr.errors import InvalidInputError
from psorr.segment import SegmentParams, colour_name, segment
from psorr.synthetic.metrics import object_segment_scores


def test_touching_boxes_of_two_colours_are_two_segments_with_their_colours():
    cloud, truth = two_boxes((RED, BLUE), gap=0.0)
    result = segment(cloud, rng=np.random.default_rng(0))
    scores = object_segment_scores(truth, result.labels)
    assert [s.iou > 0.85 for s in scores] == [True, True]
    by_colour = {s.colour: s for s in result.segments if s.n_points > 500}
    assert set(by_colour) == {"red", "blue"}
    red_box = np.flatnonzero(truth == 2)
    assert np.median(result.labels[red_box]) == by_colour["red"].id


def test_touching_boxes_of_one_colour_stay_one_segment_and_apart_they_are_two():
    cloud, truth = two_boxes((RED, RED), gap=0.0)
    touching = segment(cloud, rng=np.random.default_rng(0))
    assert len([s for s in touching.segments if s.n_points > 500]) == 1  # no cue tells them apart
    cloud, truth = two_boxes((RED, RED), gap=0.03)
    apart = segment(cloud, rng=np.random.default_rng(0))
    assert [s.iou > 0.85 for s in object_segment_scores(truth, apart.labels)] == [True, True]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_box_standing_on_another_of_its_colour_is_split_at_the_crease_between_them(seed):
    cloud, truth = stacked_boxes((RED, RED), seed=seed)
    split = segment(cloud, rng=np.random.default_rng(0))
    assert [s.iou > 0.85 for s in object_segment_scores(truth, split.labels)] == [True, True]
    whole = segment(cloud, SegmentParams(crease_noise=None), rng=np.random.default_rng(0))
    assert len([s for s in whole.segments if s.n_points > 500]) == 1  # by colour and distance alone


def test_the_table_and_nan_points_are_labelled_minus_one():
    cloud, truth = two_boxes((RED, BLUE), gap=0.0)
    result = segment(cloud, rng=np.random.default_rng(0))
    assert (result.labels[~cloud.valid_mask] == -1).all()
    assert np.mean(result.labels[truth == 1] == -1) > 0.99
    assert result.table_plane is not None and result.table_plane[3] > 0


def test_a_cloud_without_colours_is_segmented_by_distance():
    cloud, truth = two_boxes((RED, BLUE), gap=0.03)
    plain = PointCloud(cloud.points, width=cloud.width, height=cloud.height)
    result = segment(plain, rng=np.random.default_rng(0))
    assert result.stats.n_colour_models == 0 and all(s.colour is None for s in result.segments)
    assert [s.iou > 0.85 for s in object_segment_scores(truth, result.labels)] == [True, True]


def test_one_seed_gives_one_segmentation():
    cloud, _ = two_boxes((RED, BLUE), gap=0.0)
    a = segment(cloud, rng=np.random.default_rng(3))
    b = segment(cloud, rng=np.random.default_rng(3))
    assert np.array_equal(a.labels, b.labels)


@pytest.mark.parametrize("rgb, name", [((0.9, 0.05, 0.05), "red"), ((0.05, 0.2, 0.9), "blue"),
                                       ((0.97, 0.97, 0.97), "white"), ((0.2, 0.65, 0.2), "green")])
def test_colour_names(rgb, name):
    assert colour_name(rgb) == name


def test_bad_input_names_the_fix():
    with pytest.raises(InvalidInputError, match="PointCloud"):
        segment(np.zeros((10, 3)))
    with pytest.raises(InvalidInputError, match="SegmentParams"):
        segment(PointCloud(np.ones((10, 3))), params={"voxel_size": 0.01})
    with pytest.raises(InvalidInputError, match="voxel_size"):
        SegmentParams(voxel_size=0.0)
    with pytest.raises(InvalidInputError, match="crease_noise"):
        SegmentParams(crease_noise=-1.0)
