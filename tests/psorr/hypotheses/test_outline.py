"""psorr.hypotheses.outline: poses of parts resting on the table, from the patches they raise, on meshes built here."""

from __future__ import annotations

import numpy as np
import pytest
from part_meshes import box, l_bracket, open_lid, plate_with_hole, trained_library

from psorr.errors import InvalidInputError
from psorr.hypotheses.outline import OutlineMatcher, OutlineParams, cheapest, table_frame
from psorr.recognize import Recognizer
from psorr.recognize_params import RecognizeParams
from psorr.synthetic.mesh_scenes import mesh_scene
from psorr.synthetic.mesh_symmetry import find_symmetries, mesh_symmetric_add
from psorr.synthetic.resting import stable_rests
from psorr.verification.scene_view import SceneView

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")

PARTS = {"bracket": l_bracket(0.06, 0.04), "plate": plate_with_hole(), "bar": box((0.07, 0.02, 0.02)),
         "lid": open_lid()}


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    return trained_library(PARTS, tmp_path_factory.mktemp("outline"))


def _mean_offset(model, A, B) -> float:
    """The symmetry-aware ADD (metres): the plate turned over about its long axis is the same plate."""
    return mesh_symmetric_add(model.points[::10], A, B, find_symmetries(PARTS[model.name]))


def _plate_on_table():
    """The plate's lone scene (seed 0), and its measured points (N, 3) in the table's frame."""
    scene = mesh_scene(np.random.default_rng(0), PARTS, "single", names=["plate"])
    T_table_cloud = np.linalg.inv(table_frame(SceneView(scene.cloud).support_plane))
    plate = scene.cloud.points[scene.cloud.labels.reshape(-1) == 1]
    return scene, plate @ T_table_cloud[:3, :3].T + T_table_cloud[:3, 3]


def _with_points_on_table(scene, extra: np.ndarray):
    """``scene``'s measured points and ``extra`` (N, 3, the table's frame), as one unorganised cloud."""
    from psorr.types import PointCloud

    T_cloud_table = table_frame(SceneView(scene.cloud).support_plane)
    points = scene.cloud.points[scene.cloud.valid_mask]
    return PointCloud(np.vstack([points, extra @ T_cloud_table[:3, :3].T + T_cloud_table[:3, 3]]))


def test_the_table_frame_puts_the_plane_at_z_0_with_its_normal_up():
    plane = np.array([0.0, -0.6, -0.8, 0.9])
    T = table_frame(plane)
    assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3)) and np.isclose(np.linalg.det(T[:3, :3]), 1.0)
    assert np.allclose(T[:3, 2], plane[:3]) and np.isclose(plane[:3] @ T[:3, 3] + plane[3], 0.0)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_plate_lying_flat_gets_a_pose_from_its_outline_near_the_truth(library, seed):
    scene = mesh_scene(np.random.default_rng(seed), PARTS, "single", names=["plate"])
    matcher = OutlineMatcher(library.models, OutlineParams(enabled=True))
    found = matcher.candidates(scene.cloud, SceneView(scene.cloud))
    plate = library.names.index("plate")
    model = library.model("plate")
    offsets = [_mean_offset(model, c.T_cloud_model, scene.instances[0].T_camera_model)
               for c in found.candidates if c.model == plate]
    # The plate's hole is off-centre: the outline tells its two half turns apart only roughly, and ICP
    # does the rest; a start within a tenth of the diameter is what acceptance converges from.
    assert offsets and min(offsets) < 0.1 * model.diameter


def test_a_table_with_nothing_on_it_gives_no_outline_pose(library):
    scene = mesh_scene(np.random.default_rng(0), PARTS, "single", names=["plate"])
    empty = scene.cloud.points.copy()
    empty[scene.cloud.labels.reshape(-1) == 1] = np.nan  # the plate's pixels unmeasured: table alone
    from psorr.types import PointCloud

    cloud = PointCloud(empty, width=scene.cloud.width, height=scene.cloud.height)
    matcher = OutlineMatcher(library.models, OutlineParams(enabled=True))
    assert matcher.candidates(cloud, SceneView(cloud)).candidates == ()


def test_the_recognizer_with_outlines_on_finds_the_plate(library):
    scene = mesh_scene(np.random.default_rng(0), PARTS, "single", names=["plate"])
    recognizer = Recognizer(library, params=RecognizeParams(outline=OutlineParams(enabled=True)))
    detections = recognizer.recognize(scene.cloud, np.random.default_rng(0)).detections
    model = library.model("plate")
    assert [d.model for d in detections] == ["plate"]
    assert _mean_offset(model, detections[0].T_cloud_model, scene.instances[0].T_camera_model) < 0.1 * model.diameter


def test_outline_params_are_checked():
    with pytest.raises(InvalidInputError, match="cell"):
        OutlineParams(cell=0.0)
    with pytest.raises(InvalidInputError, match="rests"):
        OutlineParams(rests=0)
    with pytest.raises(InvalidInputError, match="rests"):
        OutlineParams(rests=2.0)
    assert OutlineParams().rests is None and OutlineParams(rests=3).rests == 3
    with pytest.raises(InvalidInputError, match="min_standing_share"):
        OutlineParams(min_standing_share=1.5)
    assert RecognizeParams().outline.enabled


def test_the_true_resting_pose_costs_least_and_a_wrong_model_more(library):
    scene = mesh_scene(np.random.default_rng(1), PARTS, "single", names=["bar"])
    matcher = OutlineMatcher(library.models, OutlineParams())
    view = SceneView(scene.cloud)
    T_cloud_table = table_frame(view.support_plane)
    [patch] = list(matcher._patches(scene.cloud, view.support_plane))
    poses = matcher.patch_poses(patch)
    bar = library.names.index("bar")
    assert poses[0][1] == bar
    truth = np.linalg.inv(T_cloud_table) @ scene.instances[0].T_camera_model
    best = min(_mean_offset(library.model("bar"), T, truth) for cost, m, T in poses if m == bar)
    assert best < 0.1 * library.model("bar").diameter


def test_specks_of_table_joined_to_a_patch_do_not_make_it_too_wide_for_its_part(library):
    """The table's noise lifts specks of it over the standing bar, and the closing joins those beside a part to
    its patch: 1% of the patch's points 20 mm past its far edge, low as the table's noise, take its farthest
    point past the bar's reach, yet the bar is still searched over it and posed."""
    from dataclasses import replace

    scene = mesh_scene(np.random.default_rng(1), PARTS, "single", names=["bar"])
    matcher = OutlineMatcher(library.models, OutlineParams())
    view = SceneView(scene.cloud)
    T_cloud_table = table_frame(view.support_plane)
    [patch] = list(matcher._patches(scene.cloud, view.support_plane))
    centre = patch.points[:, :2].mean(axis=0)
    away = patch.points[:, :2] - centre
    far = np.argsort(-np.linalg.norm(away, axis=1))[: len(away) // 100]
    specks = patch.points[far] + np.column_stack([0.02 * away[far] / np.linalg.norm(away[far], axis=1)[:, None],
                                                  0.003 - patch.points[far, 2]])
    specked = replace(patch, points=np.vstack([patch.points, specks]))
    bar = library.names.index("bar")
    shape = next(s for s in matcher.shapes if s.model == bar)
    assert np.linalg.norm(specked.points[:, :2] - centre, axis=1).max() > shape.reach + patch.tolerance + 0.004
    truth = np.linalg.inv(T_cloud_table) @ scene.instances[0].T_camera_model
    offsets = [_mean_offset(library.model("bar"), T, truth) for cost, m, T in matcher.patch_poses(specked) if m == bar]
    assert offsets and min(offsets) < 0.1 * library.model("bar").diameter


def test_a_lid_lying_open_side_up_is_a_patch_of_its_own_and_gets_its_pose(library):
    """A 5 mm lid on its 2 mm floor: the floor stands no higher than the table's noise, so only about a third
    of the points in the lid's cells stand (its walls), against at most a fifth in any speck of noise."""
    scene = mesh_scene(np.random.default_rng(2), PARTS, "single", names=["lid"])
    view = SceneView(scene.cloud)
    assert (np.linalg.inv(table_frame(view.support_plane)) @ scene.instances[0].T_camera_model)[2, 2] > 0.99
    model, lid = library.model("lid"), library.names.index("lid")
    for share, posed in ((OutlineParams().min_standing_share, True), (0.5, False)):
        found = OutlineMatcher(library.models, OutlineParams(min_standing_share=share)).candidates(scene.cloud, view)
        offsets = [_mean_offset(model, c.T_cloud_model, scene.instances[0].T_camera_model)
                   for c in found.candidates if c.model == lid]
        assert bool(offsets and min(offsets) < 0.1 * model.diameter) is posed, share


def test_a_plate_under_an_arm_is_its_own_patch_and_still_gets_its_pose(library):
    """Points higher than any model rests (an arm reaching in) over half of the plate: in the table's plane
    they overlap the plate's cells, and joined to its patch they would make it 15 cm high."""
    scene, local = _plate_on_table()
    cloud = _with_points_on_table(scene, local[local[:, 0] > np.median(local[:, 0])] + [0.0, 0.0, 0.15])
    matcher = OutlineMatcher(library.models, OutlineParams(enabled=True))
    found = matcher.candidates(cloud, SceneView(cloud))
    model = library.model("plate")
    offsets = [_mean_offset(model, c.T_cloud_model, scene.instances[0].T_camera_model)
               for c in found.candidates if c.model == library.names.index("plate")]
    assert offsets and min(offsets) < 0.1 * model.diameter


def test_a_part_in_its_least_probable_rest_gets_a_pose_from_every_rest_and_none_from_the_four_likeliest(library):
    # Seed 4 lays the bracket in its 5th rest (of 5, 12% likely); the search tries every rest by default.
    scene = mesh_scene(np.random.default_rng(4), PARTS, "single", names=["bracket"])
    rests = stable_rests(PARTS["bracket"])
    up = np.linalg.inv(scene.T_world_camera @ scene.instances[0].T_camera_model)[:3, 2]
    assert np.argmax([np.linalg.inv(r.T_table_model)[:3, 2] @ up for r in rests]) == 4
    model, view = library.model("bracket"), SceneView(scene.cloud)
    for params, expected in ((OutlineParams(), True), (OutlineParams(rests=4), False)):
        candidates = OutlineMatcher(library.models, params).candidates(scene.cloud, view).candidates
        near = [_mean_offset(model, c.T_cloud_model, scene.instances[0].T_camera_model) < 0.1 * model.diameter
                for c in candidates if c.model == library.names.index("bracket")]
        assert any(near) is expected, params.rests


def test_a_pose_the_sensor_sees_through_sets_no_bar_for_the_others():
    """A finned heat sink's rest fitted a gear's patch at 0.101 and the gear's own at 0.153: 1.51 times the
    cheapest, so the ratio cut the gear, and the heat sink's pose was then seen through. The bar is now the
    cheapest pose the view does not see through as placed; without one, the cheapest of all."""
    poses = [(0.101, "heat sink"), (0.153, "gear"), (0.30, "clip")]
    assert [m for _, m in cheapest(poses, 1.5)] == ["heat sink"]
    clear = lambda ps: [m != "heat sink" for _, m in ps]  # noqa: E731 (the heat sink is seen through)
    assert [m for _, m in cheapest(poses, 1.5, clear)] == ["heat sink", "gear"]
    assert [m for _, m in cheapest(poses, 1.5, lambda ps: [False] * len(ps))] == ["heat sink"]
    assert cheapest([], 1.5, clear) == []


def test_two_plates_the_closing_joins_are_searched_as_two_patches(library):
    """A second plate 3 mm beside the first: the closing of the standing cells joins them into one patch that no
    model reaches across, so the patch goes on as the two pieces its cells make without the closing, and the
    first plate is posed over its own."""
    scene, local = _plate_on_table()
    across = np.linalg.eigh(np.cov(local[:, :2].T))[1][:, 0]  # the plate's short side, on the table
    cloud = _with_points_on_table(scene, local + np.append(across * (np.ptp(local[:, :2] @ across) + 0.003), 0.0))
    matcher = OutlineMatcher(library.models, OutlineParams(enabled=True))
    patches = list(matcher._patches(cloud, SceneView(cloud).support_plane))
    assert len(patches) == 2
    found = matcher.candidates(cloud, SceneView(cloud))
    model = library.model("plate")
    offsets = [_mean_offset(model, c.T_cloud_model, scene.instances[0].T_camera_model)
               for c in found.candidates if c.model == library.names.index("plate")]
    assert offsets and min(offsets) < 0.1 * model.diameter
