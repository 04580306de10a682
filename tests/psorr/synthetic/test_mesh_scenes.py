"""psorr.synthetic.mesh_scenes: scenes of meshes built here, and their labels, poses and visibility."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from part_meshes import box, cylinder, l_bracket, plate_with_hole

from psorr.errors import CloudFileError, InvalidInputError
from psorr.synthetic.mesh_scenes import (
    DISTRACTOR_LABEL,
    OCCLUDER_LABEL,
    SceneKind,
    SceneParams,
    load_meshes,
    mesh_scene,
    simple_shapes,
)

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")

PARTS = {"bracket": l_bracket(0.06, 0.04), "plate": plate_with_hole(), "bar": box((0.07, 0.02, 0.02)),
         "roller": cylinder(0.015, 0.06)}


def _labelled(scene, label: int) -> np.ndarray:
    return scene.cloud.points[scene.cloud.labels == label]


def _distance_to(mesh: trimesh.Trimesh, T: np.ndarray, points: np.ndarray) -> np.ndarray:
    posed = mesh.copy().apply_transform(T)
    return np.abs(trimesh.proximity.signed_distance(posed, points))


def test_a_single_part_is_seen_whole_where_its_true_pose_puts_it():
    scene = mesh_scene(np.random.default_rng(0), PARTS, "single", names=["bracket"])
    assert scene.kind is SceneKind.SINGLE and [i.name for i in scene.instances] == ["bracket"]
    assert scene.cloud.width == 640 and scene.cloud.height == 480
    points = _labelled(scene, 1)
    assert len(points) > 100
    # Kinect noise at under 1.2 m is a few millimetres; the labels follow the lateral jitter.
    assert np.median(_distance_to(PARTS["bracket"], scene.instances[0].T_camera_model, points)) < 0.004
    assert scene.visibility == (pytest.approx(1.0, abs=0.02),) and 0.1 < scene.seen_share[0] < 0.7
    assert not scene.distractors


def test_parts_rest_on_the_table_in_a_stable_pose_drawn_by_its_probability():
    heights, clean = [], SceneParams(noise=None)
    for seed in range(12):
        scene = mesh_scene(np.random.default_rng(seed), PARTS, "single", names=["roller"], params=clean)
        T_world_model = scene.T_world_camera @ scene.instances[0].T_camera_model
        on_table = PARTS["roller"].vertices @ T_world_model[:3, :3].T + T_world_model[:3, 3]
        assert on_table[:, 2].min() == pytest.approx(0.0, abs=1e-9)
        heights.append(round(float(np.ptp(on_table[:, 2])), 4))
    # A roller 30 mm across and 60 mm long lies on its side with a probability of 0.89, else on an end.
    assert set(heights) <= {0.03, 0.06} and heights.count(0.03) >= 8


def test_the_camera_stays_in_its_range():
    params = SceneParams()
    for seed in range(6):
        scene = mesh_scene(np.random.default_rng(seed), PARTS, "single", names=["bar"])
        eye, forward = scene.T_world_camera[:3, 3], scene.T_world_camera[:3, 2]
        tilt = np.degrees(np.arccos(-forward[2]))
        assert params.camera_tilt_deg[0] - 1e-6 <= tilt <= params.camera_tilt_deg[1] + 1e-6
        distance = eye[2] / -forward[2]  # along the line of sight down to the table
        assert params.camera_distance[0] - 1e-6 <= distance <= params.camera_distance[1] + 1e-6


def test_clutter_holds_library_parts_and_distractors_apart():
    scene = mesh_scene(np.random.default_rng(3), PARTS, "clutter")
    names = [i.name for i in scene.instances]
    assert 3 <= len(names) <= 4 and len(set(names)) == len(names)  # 3-5, but the library has 4
    assert 1 <= len(scene.distractors) <= 3 and {d.name for d in scene.distractors} <= set(simple_shapes())
    labels = set(np.unique(scene.cloud.labels))
    assert {k + 1 for k in range(len(names))} <= labels
    assert any(DISTRACTOR_LABEL + j in labels for j in range(len(scene.distractors)))
    centres = [i.T_camera_model[:3, 3] for i in scene.instances] + [d.T_camera_model[:3, 3] for d in scene.distractors]
    assert min(np.linalg.norm(a - b) for k, a in enumerate(centres) for b in centres[k + 1:]) > 0.01
    assert OCCLUDER_LABEL not in labels and len(scene.visibility) == len(names)


def test_the_occluder_hides_parts_and_visibility_says_how_much():
    seen = [v for seed in range(4) for v in mesh_scene(np.random.default_rng(seed), PARTS, "occluded").visibility]
    assert min(seen) < 0.9  # the arm is across the parts
    assert all(0.0 <= v <= 1.0 for v in seen)
    scene = mesh_scene(np.random.default_rng(0), PARTS, "occluded")
    assert OCCLUDER_LABEL in set(np.unique(scene.cloud.labels))


def test_a_seed_gives_the_same_scene():
    a = mesh_scene(np.random.default_rng(7), PARTS, "clutter")
    b = mesh_scene(np.random.default_rng(7), PARTS, "clutter")
    assert np.array_equal(a.cloud.points, b.cloud.points, equal_nan=True)
    assert all(np.array_equal(x.T_camera_model, y.T_camera_model) for x, y in zip(a.instances, b.instances))


def test_meshes_are_read_from_a_folder_in_their_units(tmp_path):
    box((60.0, 40.0, 20.0)).export(tmp_path / "block.stl")
    meshes = load_meshes(tmp_path, "mm")
    assert list(meshes) == ["block"] and meshes["block"].extents == pytest.approx((0.06, 0.04, 0.02))


def test_bad_input_names_the_fix(tmp_path):
    with pytest.raises(CloudFileError, match="no such folder"):
        load_meshes(tmp_path / "missing", "mm")
    with pytest.raises(CloudFileError, match="holds no mesh files"):
        load_meshes(tmp_path, "mm")
    with pytest.raises(InvalidInputError, match="unknown parts"):
        mesh_scene(np.random.default_rng(0), PARTS, "single", names=["gear"])
    with pytest.raises(InvalidInputError, match="unknown scene kind"):
        mesh_scene(np.random.default_rng(0), PARTS, "heap")
    with pytest.raises(InvalidInputError, match="must not be a library part"):
        mesh_scene(np.random.default_rng(0), PARTS, "clutter", distractors={"bar": box()})
    with pytest.raises(InvalidInputError, match="camera_distance"):
        SceneParams(camera_distance=(1.0, 0.5))
