"""A look at the held part tells its near-symmetric twins apart (sim/skills/in_hand.py). Headless."""

import numpy as np
import pytest

from psorr.synthetic.catalog import load_catalog
from psorr.verification.depth_compare import DepthRenderer
from sim.control.cell import ArmCell
from sim.skills.in_hand import telling_pixels, turned_about_vertical
from sim.skills.perception import Perception
from sim.skills.pick import pick_and_place
from sim.world import WorldConfig, build_world

END_FOR_END = np.diag([-1.0, -1.0, 1.0, 1.0])  # the chassis' half turn about its height (its frame is centred)


def _chassis_cell(seed: int):
    world = build_world(WorldConfig(workpieces=("chassis",)), np.random.default_rng(seed))
    world.reset()
    return world, Perception(world, np.random.default_rng(seed), recognize=True, rgb=False)


def test_the_twins_differ_at_more_pixels_with_the_end_walls_towards_the_camera():
    """From 30 degrees off vertical, a chassis lying across the view shows its end walls edge-on; turned a
    quarter turn, one end wall faces the camera and the other's inside is in view."""
    mesh = load_catalog()["chassis"].load_mesh()
    renderer = DepthRenderer(mesh.vertices, mesh.faces)
    world = build_world(WorldConfig(workpieces=("chassis",)), np.random.default_rng(0))
    intrinsics = world.config.intrinsics
    T_camera_world = np.linalg.inv(world.T_world_camera)
    x_across = T_camera_world[:3, :3].T @ [1.0, 0.0, 0.0]  # the image's x axis, in the world
    yaw = np.arctan2(x_across[1], x_across[0])
    T = np.eye(4)
    T[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
    T[:3, 3] = (0.0, 0.0, world.table_top + 0.1)
    counts = []
    for turn in (0.0, 90.0):
        T_part = turned_about_vertical(T, turn)
        poses = T_camera_world @ np.array([T_part, T_part @ END_FOR_END])
        counts.append(telling_pixels(renderer, poses, intrinsics, 0.1))
    assert counts[1] > 1.5 * counts[0] > 0


@pytest.mark.parametrize("estimate_turned", [True, False])
def test_a_chassis_is_seated_the_way_round_the_look_in_the_hand_finds(estimate_turned):
    """Picked from the chassis turned end for end, with the true pose as the twin the first look could not
    rule out (or the other way about): the look in the hand finds which it is, and the place follows it."""
    world, perception = _chassis_cell(1)
    with perception:
        T_true = world.body_pose("chassis")
        estimate, twin = (T_true @ END_FOR_END, T_true) if estimate_turned else (T_true, T_true @ END_FOR_END)
        pick = pick_and_place(world, "chassis", estimate, ArmCell(world), (twin,), perception)
    assert pick.in_hand is not None and pick.in_hand.settled
    assert pick.in_hand.chosen == (1 if estimate_turned else 0)
    assert pick.in_hand.telling_pixels > 100
    assert pick.placed, pick.note
    assert pick.rot_error_deg > 170 if estimate_turned else pick.rot_error_deg < 5


def test_without_eyes_the_twin_is_not_looked_for():
    """No perception: the alternatives cannot be judged, and the chassis is seated as estimated, turned."""
    world = build_world(WorldConfig(workpieces=("chassis",)), np.random.default_rng(1))
    world.reset()
    T_true = world.body_pose("chassis")
    pick = pick_and_place(world, "chassis", T_true @ END_FOR_END, ArmCell(world), (T_true,))
    assert pick.in_hand is None and pick.grasped and not pick.placed


def test_samples_behind_the_fingers_count_as_hidden_not_as_unseen():
    """A look is judged by what the arm leaves in view: with a finger over half a chassis at its true pose,
    the pose scores as it does with nothing over it, where the cloud PSORR refines on (the finger's pixels
    removed) scores it by the samples left."""
    from psorr.library.models import ModelLibrary
    from psorr.synthetic.workpiece_scenes import workpiece_scene
    from psorr.types import Detection
    from psorr.verification.point_check import check_pose
    from psorr.verification.scene_view import SceneView
    from sim.skills.in_hand import unhidden_score
    from sim.skills.looks import HeldLook

    entry = load_catalog()["chassis"]
    scene = workpiece_scene(np.random.default_rng(3), {"chassis": entry.load_mesh()}, ["chassis"])
    model = ModelLibrary.from_meshes([entry.mesh_path]).model("chassis")
    T = scene.instances[0].T_camera_model
    cloud = scene.cloud
    on_part = cloud.labels == 1
    u = np.arange(len(cloud.points)) % cloud.width
    finger = on_part & (u < np.median(u[on_part]))  # the left half of the part's pixels
    nearer = cloud.points.copy()
    nearer[finger] *= 0.9  # the finger, 10% nearer along the same rays
    without = cloud.points.copy()
    without[finger] = np.nan
    with_arm = type(cloud)(nearer, width=cloud.width, height=cloud.height)
    refined_on = type(cloud)(without, width=cloud.width, height=cloud.height)
    bare = check_pose(SceneView(cloud), model.points, model.normals, T)
    removed = check_pose(SceneView(refined_on), model.points, model.normals, T).score
    look = HeldLook(Detection("chassis", T, removed, removed), np.eye(4), with_arm)
    no_finger = HeldLook(look.detection, np.eye(4), cloud)
    assert removed < 0.7 * bare.score
    assert unhidden_score(no_finger, model) == pytest.approx(bare.unblocked_fraction * (1 - bare.violation_ratio))
    assert unhidden_score(look, model) == pytest.approx(unhidden_score(no_finger, model), abs=0.05)
