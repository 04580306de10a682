"""Recognizer.recognize(..., known=...): an earlier look's parts followed, and only what they leave searched."""

import numpy as np
import pytest

from psorr.errors import InvalidInputError
from psorr.recognize import Recognizer
from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import Detection, PointCloud

NAMES = ["transformer", "u_channel", "flanged_hub"]


@pytest.fixture(scope="module")
def scene():
    catalog = load_catalog()
    return workpiece_scene(np.random.default_rng(4), {n: catalog[n].load_mesh() for n in NAMES}, NAMES)


@pytest.fixture(scope="module")
def first_look(library, scene):
    return Recognizer(library).recognize(scene.cloud, np.random.default_rng(0))


def _without(scene, label: int) -> PointCloud:
    """The scene's cloud with one instance's points gone (taken away, its table not yet seen)."""
    c = scene.cloud
    points = np.where((c.labels == label)[:, None], np.nan, c.points)
    return PointCloud(points, width=c.width, height=c.height)


def _found(detections, scene, library) -> set[str]:
    """The models of ``detections`` within ADD 0.1 d of their true instance."""
    catalog, out = load_catalog(), set()
    for d in detections:
        inst = next(i for i in scene.instances if i.name == d.model)
        model = library.model(d.model)
        add = symmetric_add(model.points[::10], d.T_cloud_model, inst.T_camera_model, catalog[d.model])
        if add < 0.1 * model.diameter:
            out.add(d.model)
    return out


def test_a_look_again_follows_the_parts_found_and_drops_the_one_taken(library, scene, first_look):
    assert _found(first_look.detections, scene, library) == set(NAMES)
    gone = next(k for k, i in enumerate(scene.instances) if i.name == "u_channel") + 1
    again = Recognizer(library).recognize(_without(scene, gone), np.random.default_rng(0), known=first_look.detections)
    assert sorted(d.model for d in again.detections) == ["flanged_hub", "transformer"]
    assert _found(again.detections, scene, library) == {"flanged_hub", "transformer"}
    assert again.stats.hypotheses < first_look.stats.hypotheses  # nothing left standing to search


def test_a_nudged_part_is_followed_to_where_it_lies(library, scene, first_look):
    turn = np.radians(3.0)
    nudge = np.eye(4)
    nudge[:2, :2] = [[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]]
    nudge[:3, 3] = (0.003, -0.002, 0.0)
    known = [Detection(d.model, d.T_cloud_model @ nudge, d.score) for d in first_look.detections]
    again = Recognizer(library).recognize(scene.cloud, np.random.default_rng(0), known=known)
    assert _found(again.detections, scene, library) == set(NAMES)
    assert len(again.detections) == len(NAMES)  # each once: the followed pose keeps its pixels


def test_known_must_be_detections_of_the_librarys_models(library, scene, first_look):
    recognizer = Recognizer(library)
    with pytest.raises(InvalidInputError, match="sequence of Detections"):
        recognizer.recognize(scene.cloud, known=first_look.detections[0])
    with pytest.raises(InvalidInputError, match=r"known\[0\] must be a Detection"):
        recognizer.recognize(scene.cloud, known=[np.eye(4)])
    with pytest.raises(InvalidInputError, match="'sprocket'.*holds .*chassis"):
        recognizer.recognize(scene.cloud, known=[Detection("sprocket", np.eye(4), 0.5)])
    with pytest.raises(InvalidInputError, match="PSORR, PSG and auto methods.*orr"):
        Recognizer(library, method="orr").recognize(scene.cloud, known=first_look.detections)
