"""Recognizer.refine, a second look at a part already found, and the checks a Detection makes of its poses."""

import numpy as np
import pytest

from psorr.errors import InvalidInputError
from psorr.recognize import Recognizer
from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import Detection


@pytest.fixture(scope="module")
def catalog():
    return load_catalog()


def test_refine_takes_a_rough_pose_of_a_known_part_to_its_place(library, catalog):
    """A look again at a part already found: from 6 mm and 4 degrees off, refine lands within ADD 0.02 d."""
    names = ["transformer"]
    scene = workpiece_scene(np.random.default_rng(2), {n: catalog[n].load_mesh() for n in names}, names)
    T_true = scene.instances[0].T_camera_model
    a = np.radians(4.0)
    off = np.eye(4)
    off[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    off[:3, 3] = (0.004, -0.003, 0.003)
    detection = Recognizer(library).refine(scene.cloud, "transformer", T_true @ off)
    model = library.model("transformer")
    assert detection.model == "transformer" and detection.score > 0.5
    assert symmetric_add(model.points[::10], detection.T_cloud_model, T_true, catalog["transformer"]) \
        < 0.02 * model.diameter
    assert detection.alternatives == ()  # its half turns are exact symmetries: nothing to tell apart


def test_refine_names_the_models_it_knows_and_wants_a_pose(library, catalog):
    scene = workpiece_scene(np.random.default_rng(9), {}, [])
    with pytest.raises(InvalidInputError, match="chassis"):
        Recognizer(library).refine(scene.cloud, "chasis", np.eye(4))
    with pytest.raises(InvalidInputError, match=r"\(4, 4\)"):
        Recognizer(library).refine(scene.cloud, "chassis", np.eye(3))
    with pytest.raises(InvalidInputError, match="got NaN or inf in it"):
        Recognizer(library).refine(scene.cloud, "chassis", np.full((4, 4), np.nan))
    with pytest.raises(InvalidInputError, match="T_cloud_model must be a rigid transform"):
        Recognizer(library).refine(scene.cloud, "chassis", 2 * np.eye(4))
    in_millimetres = np.eye(4)
    in_millimetres[:3, 3] = (12.0, -40.0, 850.0)
    with pytest.raises(InvalidInputError, match="851 m from the sensor.*divide it by 1000"):
        Recognizer(library).refine(scene.cloud, "chassis", in_millimetres)


def test_a_detection_checks_its_alternatives_like_its_pose():
    with pytest.raises(InvalidInputError, match=r"alternatives\[0\].*\(4, 4\)"):
        Detection("chassis", np.eye(4), 0.5, 0.5, (np.eye(3),))
    with pytest.raises(InvalidInputError, match=r"alternatives\[1\].*rigid"):
        Detection("chassis", np.eye(4), 0.5, 0.5, (np.eye(4), 2 * np.eye(4)))
    detection = Detection("chassis", np.eye(4), 0.5, 0.5, [np.eye(4).tolist()])
    assert isinstance(detection.alternatives, tuple) and not detection.alternatives[0].flags.writeable
