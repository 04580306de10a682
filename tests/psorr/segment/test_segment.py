"""Colour segmentation (psorr.segment): boxes told apart by colour, the table left out, colour names."""

import numpy as np
import pytest
import trimesh

from psorr import PointCloud
from psorr.errors import InvalidInputError
from psorr.segment import SegmentParams, colour_name, segment
from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, look_at
from psorr.sensing.kinect_noise import kinect_noise_with_source
from psorr.sensing.raycast import render_meshes
from psorr.synthetic.metrics import object_segment_scores

RED, BLUE, GREY = (0.8, 0.1, 0.1), (0.1, 0.25, 0.8), (0.55, 0.5, 0.45)


def _two_boxes(colours, gap: float, seed: int = 0) -> tuple[PointCloud, np.ndarray]:
    """Two identical 10 x 6 x 5 cm boxes side by side ``gap`` metres apart on a table, seen by a Kinect
    from 0.8 m, coloured ``colours`` with a little colour noise; and the truth: 1 table, 2 and 3 the boxes."""
    table = trimesh.creation.box((0.8, 0.8, 0.02))
    table.apply_translation((0, 0, -0.01))
    boxes = []
    for k in range(2):
        box = trimesh.creation.box((0.10, 0.06, 0.05))
        box.apply_translation((0.0, (k - 0.5) * (0.06 + gap), 0.025))
        boxes.append(box)
    intrinsics = CameraIntrinsics()
    rng = np.random.default_rng(seed)
    depth, ids = render_meshes([(table, 1), (boxes[0], 2), (boxes[1], 3)], look_at((0.45, -0.2, 0.65), (0, 0, 0)),
                               intrinsics)
    noisy, source = kinect_noise_with_source(depth, intrinsics, rng)
    truth = ids.ravel()[source.ravel()]
    palette = np.array([GREY, GREY, *colours])  # ids -1 (nothing) and 1 (table) grey
    rgb = np.clip(palette[np.clip(truth, 0, 3)] + rng.normal(0, 0.02, (len(truth), 3)), 0, 1)
    cloud = depth_to_cloud(noisy, intrinsics, colors=rgb.reshape(intrinsics.height, intrinsics.width, 3))
    return cloud, np.where(cloud.valid_mask, truth, -1)


def test_touching_boxes_of_two_colours_are_two_segments_with_their_colours():
    cloud, truth = _two_boxes((RED, BLUE), gap=0.0)
    result = segment(cloud, rng=np.random.default_rng(0))
    scores = object_segment_scores(truth, result.labels)
    assert [s.iou > 0.85 for s in scores] == [True, True]
    by_colour = {s.colour: s for s in result.segments if s.n_points > 500}
    assert set(by_colour) == {"red", "blue"}
    red_box = np.flatnonzero(truth == 2)
    assert np.median(result.labels[red_box]) == by_colour["red"].id


def test_touching_boxes_of_one_colour_stay_one_segment_and_apart_they_are_two():
    cloud, truth = _two_boxes((RED, RED), gap=0.0)
    touching = segment(cloud, rng=np.random.default_rng(0))
    assert len([s for s in touching.segments if s.n_points > 500]) == 1  # no cue tells them apart
    cloud, truth = _two_boxes((RED, RED), gap=0.03)
    apart = segment(cloud, rng=np.random.default_rng(0))
    assert [s.iou > 0.85 for s in object_segment_scores(truth, apart.labels)] == [True, True]


def test_the_table_and_nan_points_are_labelled_minus_one():
    cloud, truth = _two_boxes((RED, BLUE), gap=0.0)
    result = segment(cloud, rng=np.random.default_rng(0))
    assert (result.labels[~cloud.valid_mask] == -1).all()
    assert np.mean(result.labels[truth == 1] == -1) > 0.99
    assert result.table_plane is not None and result.table_plane[3] > 0


def test_a_cloud_without_colours_is_segmented_by_distance():
    cloud, truth = _two_boxes((RED, BLUE), gap=0.03)
    plain = PointCloud(cloud.points, width=cloud.width, height=cloud.height)
    result = segment(plain, rng=np.random.default_rng(0))
    assert result.stats.n_colour_models == 0 and all(s.colour is None for s in result.segments)
    assert [s.iou > 0.85 for s in object_segment_scores(truth, result.labels)] == [True, True]


def test_one_seed_gives_one_segmentation():
    cloud, _ = _two_boxes((RED, BLUE), gap=0.0)
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
