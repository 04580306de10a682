"""A detection found on shape alone is given the colour of the points that support it."""

import dataclasses

import numpy as np
import pytest
from coloured_scenes import BLUE, RED, two_boxes
from part_meshes import box, trained_library

from psorr.errors import InvalidInputError
from psorr.recognize import Recognizer
from psorr.segment import supported_colour


@pytest.fixture(scope="module")
def boxes(tmp_path_factory):
    return trained_library({"box": box((0.10, 0.06, 0.05))}, tmp_path_factory.mktemp("boxes"))


@pytest.fixture(scope="module")
def scene(boxes):
    cloud, truth = two_boxes((RED, BLUE), gap=0.03)
    detections = Recognizer(boxes).recognize(cloud, np.random.default_rng(0)).detections
    return cloud, truth, detections


def test_each_box_found_on_shape_gets_its_own_colour(boxes, scene):
    cloud, truth, detections = scene
    assert len(detections) == 2
    for detection in detections:
        colour = supported_colour(cloud, detection, boxes.model("box"))
        nearest = min((2, 3), key=lambda label: np.linalg.norm(
            cloud.points[truth == label].mean(axis=0) - detection.T_cloud_model[:3, 3]))
        assert colour.name == {2: "red", 3: "blue"}[nearest]
        assert np.allclose(colour.mean_rgb, RED if nearest == 2 else BLUE, atol=0.1)


def test_a_cloud_without_colours_gives_none(boxes, scene):
    cloud, _, detections = scene
    assert supported_colour(dataclasses.replace(cloud, colors=None), detections[0], boxes.model("box")) is None


def test_a_pose_away_from_every_point_gives_none(boxes, scene):
    cloud, _, detections = scene
    T = detections[0].T_cloud_model.copy()
    T[2, 3] += 5.0
    far = dataclasses.replace(detections[0], T_cloud_model=T)
    assert supported_colour(cloud, far, boxes.model("box")) is None


def test_the_model_must_be_the_detections(boxes, scene, tmp_path):
    cloud, _, detections = scene
    other = trained_library({"slab": box((0.08, 0.08, 0.02))}, tmp_path)
    with pytest.raises(InvalidInputError, match="library.model"):
        supported_colour(cloud, detections[0], other.model("slab"))
