"""A finer sensor than the Kinect: a 1280x720 view of the clutter, seen by recognition as by a Kinect."""

import numpy as np
import pytest

from psorr.recognize import Recognizer
from psorr.sensing.camera import CameraIntrinsics
from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.verification.scene_view import SceneView

HD = CameraIntrinsics(width=1280, height=720, fx=910.0, fy=910.0, cx=639.5, cy=359.5)


def test_one_instance_is_reported_once_on_a_finer_image(library):
    catalog = load_catalog()
    names = ["circuit_board", "chassis", "flanged_hub", "transformer"]  # the clutter of seed 0
    scene = workpiece_scene(np.random.default_rng(1000), {n: catalog[n].load_mesh() for n in names}, names,
                            intrinsics=HD, occluder=True)
    view = SceneView(scene.cloud)
    assert view.focal == pytest.approx(910.0)  # the grid's own, not a Kinect's 1050 (a quarter of pixels empty)
    assert view.claim_block == 7  # as wide in metres as a Kinect's 4 pixels: 4-pixel cells let the chassis in twice
    detections = Recognizer(library).recognize(scene.cloud, np.random.default_rng(0)).detections
    for k, a in enumerate(detections):
        samples = library.model(a.model).points[::10]
        for b in detections[k + 1:]:
            if b.model == a.model:
                apart = symmetric_add(samples, a.T_cloud_model, b.T_cloud_model, catalog[a.model])
                assert apart > 0.1 * library.model(a.model).diameter, f"{a.model} reported twice"
    assert [d.model for d in detections].count("chassis") == 1


def test_a_bracket_first_posed_as_its_twin_is_reported_at_its_true_pose(library):
    # The clutter of seed 34 at 1280x720: the bracket's best-scoring candidate, 0.10 diameters off, is
    # taken by its near-symmetry to the legs-swapped twin, and kept the pixels from a candidate that the
    # near-symmetry takes to the true pose. The loser's second chance, at the pose it resolves to, wins.
    catalog = load_catalog()
    names = list(np.random.default_rng(34).choice(sorted(catalog), size=4, replace=False))
    assert "bracket" in names
    scene = workpiece_scene(np.random.default_rng(1034), {n: catalog[n].load_mesh() for n in names}, names,
                            intrinsics=HD, occluder=True)
    truth = next(i for i in scene.instances if i.name == "bracket").T_camera_model
    brackets = [d for d in Recognizer(library).recognize(scene.cloud, np.random.default_rng(0)).detections
                if d.model == "bracket"]
    model = library.model("bracket")
    assert len(brackets) == 1
    assert symmetric_add(model.points, brackets[0].T_cloud_model, truth, catalog["bracket"]) < 0.1 * model.diameter


def _chassis_under_the_arm(library):
    """The clutter of seed 18 at 1280x720: the arm hides most of the chassis (0.42 of it in view). Returns
    the chassis's true pose and the detections."""
    catalog = load_catalog()
    names = list(np.random.default_rng(18).choice(sorted(catalog), size=4, replace=False))
    assert "chassis" in names and "bracket" not in names
    scene = workpiece_scene(np.random.default_rng(1018), {n: catalog[n].load_mesh() for n in names}, names,
                            intrinsics=HD, occluder=True)
    truth = next(i for i in scene.instances if i.name == "chassis").T_camera_model
    return truth, Recognizer(library).recognize(scene.cloud, np.random.default_rng(0)).detections


def test_no_bracket_is_posed_on_the_walls_of_a_chassis_under_an_arm(library):
    # L brackets posed on the chassis's walls score 0.57 and 0.54, and are seen through by 0.08 and 0.11
    # (within a pixel): over the 0.05 bar. Counted pixel by pixel they were 0.11-0.13, and passed the old
    # 0.15 bar, to be displaced by the chassis only because it explained clearly more.
    _, detections = _chassis_under_the_arm(library)
    assert "bracket" not in [d.model for d in detections]


def test_a_chassis_under_an_arm_is_found(library):
    # No pair gives the chassis a start; the resting search over the table cells the arm hides does
    # (docs/decisions/0071-partly-hidden-resting-parts.md): without it, the bushing, tee and hub alone.
    truth, detections = _chassis_under_the_arm(library)
    chassis = [d for d in detections if d.model == "chassis"]
    model = library.model("chassis")
    assert len(chassis) == 1
    add = symmetric_add(model.points, chassis[0].T_cloud_model, truth, load_catalog()["chassis"])
    assert add < 0.1 * model.diameter
