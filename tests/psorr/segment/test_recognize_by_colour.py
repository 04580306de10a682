"""Shape plus colour: two identical boxes, one red and one blue, recognised with their colours."""

import numpy as np
import pytest
from coloured_scenes import BLUE, RED, two_boxes
from part_meshes import box, trained_library

from psorr.errors import InvalidInputError
from psorr.recognize import Recognizer


@pytest.fixture(scope="module")
def boxes(tmp_path_factory):
    return trained_library({"box": box((0.10, 0.06, 0.05))}, tmp_path_factory.mktemp("boxes"))


def _centre(detection) -> np.ndarray:
    return detection.T_cloud_model[:3, 3]


def test_two_touching_boxes_are_recognised_with_their_colours(boxes):
    cloud, truth = two_boxes((RED, BLUE), gap=0.0)
    detections = Recognizer(boxes, use_colour=True).recognize(cloud, np.random.default_rng(0)).detections
    assert sorted(d.colour.name for d in detections) == ["blue", "red"]
    for colour, label in (("red", 2), ("blue", 3)):
        found = next(d for d in detections if d.colour.name == colour)
        truth_centre = cloud.points[truth == label].mean(axis=0)  # the seen surface's middle, near the box's
        assert np.linalg.norm(_centre(found) - truth_centre) < 0.03
        assert found.model == "box" and len(found.colour.mean_rgb) == 3


def test_without_colour_detections_carry_none(boxes):
    cloud, _ = two_boxes((RED, BLUE), gap=0.03)
    detections = Recognizer(boxes).recognize(cloud, np.random.default_rng(0)).detections
    assert detections and all(d.colour is None for d in detections)


def test_use_colour_must_be_a_flag(boxes):
    with pytest.raises(InvalidInputError, match="use_colour"):
        Recognizer(boxes, use_colour="yes")
