"""psorr.hypotheses.hidden_rests: resting poses of parts an arm hides in part, on meshes built here."""

from __future__ import annotations

import numpy as np
import pytest
from part_meshes import box, l_bracket, plate_with_hole, trained_library

from psorr.hypotheses.hidden_rests import HiddenRests, hidden_cells
from psorr.hypotheses.outline import OutlineMatcher, OutlineParams
from psorr.hypotheses.standing_patches import standing_grid, table_frame
from psorr.synthetic.mesh_scenes import mesh_scene
from psorr.synthetic.mesh_symmetry import find_symmetries, mesh_symmetric_add
from psorr.types import PointCloud
from psorr.verification.scene_view import SceneView

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")

PARTS = {"bracket": l_bracket(0.06, 0.04), "plate": plate_with_hole(), "bar": box((0.07, 0.02, 0.02))}
ARM_HEIGHT = 0.15  # metres above the table: higher than any part here rests


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    return trained_library(PARTS, tmp_path_factory.mktemp("hidden_rests"))


def _under_an_arm(scene, share: float, measured: bool = True) -> PointCloud:
    """The scene's cloud with an arm 15 cm above the table across the far ``share`` of its part (along the
    table's x) and 5 cm of table past it: every point there is moved along its ray onto the arm, as the
    sensor would see it, so the part's points under the arm are gone. Not ``measured``: the arm is nearer
    than the sensor's range, and gives no points at all."""
    points = scene.cloud.points.reshape(-1, 3).copy()
    plane = SceneView(scene.cloud).support_plane
    T_table_cloud = np.linalg.inv(table_frame(plane))
    local = points @ T_table_cloud[:3, :3].T + T_table_cloud[:3, 3]
    part = local[scene.cloud.labels.reshape(-1) == 1]
    low, high = part[:, 0].min(), part[:, 0].max()
    with np.errstate(invalid="ignore"):
        arm = ((local[:, 0] > high - share * (high - low)) & (local[:, 0] < high + 0.05)
               & (np.abs(local[:, 1] - part[:, 1].mean()) < 0.06))
    points[arm] *= ((ARM_HEIGHT - plane[3]) / (points[arm] @ plane[:3]))[:, None] if measured else np.nan
    return PointCloud(points, width=scene.cloud.width, height=scene.cloud.height)


def _best_offset(library, found, scene, name: str) -> float | None:
    """The least symmetry-aware ADD, over the diameter, of ``found``'s poses of ``name``; None if it has none."""
    model = library.model(name)
    truth = scene.instances[0].T_camera_model
    offsets = [mesh_symmetric_add(model.points[::10], c.T_cloud_model, truth, find_symmetries(PARTS[name]))
               for c in found.candidates if c.model == library.names.index(name)]
    return min(offsets) / model.diameter if offsets else None


def test_a_plate_half_under_an_arm_is_posed_over_the_cells_the_arm_hides(library):
    """Half the plate hidden: its patch's centre lies a quarter of the plate from the plate's, beyond the
    ordinary search's shifts, and its silhouette covers table the sensor never saw; the ordinary search
    finds no pose of the plate, the search over hidden cells its true one."""
    scene = mesh_scene(np.random.default_rng(1), PARTS, "single", names=["plate"])
    cloud = _under_an_arm(scene, 0.5)
    view = SceneView(cloud)
    outline = OutlineMatcher(library.models, OutlineParams())
    assert _best_offset(library, outline.candidates(cloud, view), scene, "plate") is None
    best = _best_offset(library, HiddenRests(outline).candidates(cloud, view), scene, "plate")
    assert best is not None and best < 0.1


def test_hidden_cells_are_those_under_the_arm_and_no_patch_holds_them(library):
    scene = mesh_scene(np.random.default_rng(1), PARTS, "single", names=["plate"])
    outline = OutlineMatcher(library.models, OutlineParams())
    for cloud, hides in ((scene.cloud, False), (_under_an_arm(scene, 0.5), True)):
        view = SceneView(cloud)
        grid = standing_grid(cloud, view.support_plane, outline.params, outline.tallest, outline.check, 0.05)
        hidden = hidden_cells(grid, view, view.support_plane, outline.tallest, outline.check)
        assert bool(hidden.any()) is hides
        assert not (hidden & (grid.labels > 0)).any()


def test_with_nothing_above_the_parts_no_patch_is_searched_again(library):
    scene = mesh_scene(np.random.default_rng(1), PARTS, "single", names=["plate"])
    found = HiddenRests(OutlineMatcher(library.models, OutlineParams())).candidates(scene.cloud, SceneView(scene.cloud))
    assert not found.candidates and found.regions == 0


def test_hidden_border_none_turns_the_search_off(library):
    scene = mesh_scene(np.random.default_rng(1), PARTS, "single", names=["plate"])
    cloud = _under_an_arm(scene, 0.5)
    outline = OutlineMatcher(library.models, OutlineParams(hidden_border=None))
    assert not HiddenRests(outline).candidates(cloud, SceneView(cloud)).candidates


def test_the_recognizer_finds_the_plate_half_under_the_arm_only_with_the_search(library):
    from dataclasses import replace

    from psorr.recognize import Recognizer
    from psorr.recognize_params import RecognizeParams

    scene = mesh_scene(np.random.default_rng(1), PARTS, "single", names=["plate"])
    cloud = _under_an_arm(scene, 0.5)
    model = library.model("plate")
    for border, found in ((OutlineParams().hidden_border, True), (None, False)):
        params = replace(RecognizeParams(), outline=OutlineParams(hidden_border=border))
        detections = Recognizer(library, params=params).recognize(cloud, np.random.default_rng(0)).detections
        offsets = [mesh_symmetric_add(model.points[::10], d.T_cloud_model, scene.instances[0].T_camera_model,
                                      find_symmetries(PARTS["plate"])) for d in detections if d.model == "plate"]
        assert bool(offsets and min(offsets) < 0.1 * model.diameter) is found, border


def test_a_plate_half_under_an_arm_the_sensor_cannot_measure_is_found(library):
    """The arm nearer than the sensor's range leaves a hole with no points: its cells are hidden, the plate's
    samples there count as hidden rather than unseen, and the plate is found at its true pose; in the same
    points stripped of the image's grid (what is missing there may have been cropped away), it is not."""
    from psorr.recognize import Recognizer
    from psorr.verification.point_check import check_pose

    scene = mesh_scene(np.random.default_rng(1), PARTS, "single", names=["plate"])
    cloud = _under_an_arm(scene, 0.5, measured=False)
    model, truth = library.model("plate"), scene.instances[0].T_camera_model
    check = check_pose(SceneView(cloud), model.points, model.normals, truth)
    assert check.n_occluded > 0.3 * check.n_visible and check.unblocked_fraction > 0.9
    points = cloud.points.reshape(-1, 3)
    for given, found in ((cloud, True), (PointCloud(points[np.isfinite(points).all(axis=1)]), False)):
        detections = Recognizer(library).recognize(given, np.random.default_rng(0)).detections
        offsets = [mesh_symmetric_add(model.points[::10], d.T_cloud_model, truth, find_symmetries(PARTS["plate"]))
                   for d in detections if d.model == "plate"]
        assert bool(offsets and min(offsets) < 0.1 * model.diameter) is found
