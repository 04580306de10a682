"""The arm MJCF (UR5e kinematics + parallel gripper) and its config, alone and attached into a scene. Headless."""

import mujoco
import numpy as np
import pytest
from arm_scenes import CFG, TOOL_DOWN, arm_scene, tool_pose

from sim.control.ik import ArmIK, T_world_site
from sim.world.robot import load_arm_spec

TOOL_OFFSET = 0.1175  # m from the flange to the grasp point, along the flange z
# Standard DH of the UR5e: (d, a, alpha) per joint, theta = joint angle.
UR5E_DH = [(0.1625, 0.0, np.pi / 2), (0.0, -0.425, 0.0), (0.0, -0.3922, 0.0),
           (0.1333, 0.0, np.pi / 2), (0.0997, 0.0, -np.pi / 2), (0.0996, 0.0, 0.0)]  # fmt: skip


@pytest.fixture(scope="module")
def model():
    return load_arm_spec().compile()


def at_home(model):
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key(CFG.home_key).id)
    mujoco.mj_forward(model, data)
    return data


def step(model, data, n):
    for _ in range(n):
        mujoco.mj_step(model, data)


def warning_counts(data):
    return {mujoco.mjtWarning(i).name: int(w.number) for i, w in enumerate(data.warning) if w.number}


def dh_T_base_tool(q):
    """Forward kinematics straight from the DH table, independent of the MJCF."""
    T = np.eye(4)
    for theta, (d, a, alpha) in zip(q, UR5E_DH):
        ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
        T = T @ np.array(
            [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]]
        )
    tool = np.eye(4)
    tool[2, 3] = TOOL_OFFSET
    return T @ tool


def arm_q(model, q):
    return np.array([q[model.joint(j).qposadr[0]] for j in CFG.arm_joints])


def pad_gap(model, data):
    """Distance between the inner faces of the pads along the closing axis (m)."""
    R = data.site_xmat[model.site(CFG.tool_site).id].reshape(3, 3)
    left, right = (model.geom(g) for g in CFG.pad_geoms)
    x_left, x_right = (R[:, 0] @ data.geom_xpos[g.id] for g in (left, right))
    return abs(x_left - x_right) - left.size[0] - right.size[0]


def test_arm_compiles_with_every_configured_name(model):
    assert (model.nq, model.nv, model.nu) == (8, 8, 7)
    for j in (*CFG.arm_joints, *CFG.finger_joints):
        model.joint(j)
    for a in (*CFG.arm_actuators, CFG.gripper_actuator):
        model.actuator(a)
    for g in (*CFG.pad_geoms, *CFG.collision_geoms):
        assert model.geom(g).contype[0] and model.geom(g).group[0] == 3
    assert sorted(model.body_mass[2:8].round(2)) == sorted([3.7, 8.4, 2.3, 1.2, 1.2, 0.25])
    assert np.allclose(model.jnt_range[model.joint("elbow_joint").id], [-np.pi, np.pi], atol=1e-5)
    pad = model.geom(CFG.pad_geoms[0])
    assert pad.friction[0] == pytest.approx(1.5) and pad.condim[0] == 4


def test_home_holds_still_without_warnings(model):
    data = at_home(model)
    start = T_world_site(model, data, CFG.tool_site)
    assert data.ncon == 0
    step(model, data, 500)
    assert warning_counts(data) == {}
    assert np.linalg.norm(T_world_site(model, data, CFG.tool_site)[:3, 3] - start[:3, 3]) < 1e-3
    assert np.abs(data.qvel).max() < 1e-3


def test_random_position_targets_stay_finite(model):
    rng = np.random.default_rng(7)
    lo, hi = model.actuator_ctrlrange.T
    for _ in range(5):
        data = at_home(model)
        data.ctrl[:] = rng.uniform(lo, hi)
        step(model, data, 500)
        assert warning_counts(data) == {}
        assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
        # Limits hold; the arm was moving towards the targets.
        assert np.all(data.qpos >= model.jnt_range[:, 0] - 1e-2) and np.all(data.qpos <= model.jnt_range[:, 1] + 1e-2)


def test_home_points_the_tool_down_over_the_table(model):
    T = T_world_site(model, at_home(model), CFG.tool_site)
    angle = np.degrees(np.arccos(np.clip(T[:3, 2] @ [0, 0, -1], -1, 1)))
    assert angle < 1.0
    assert np.allclose(T[:3, 3], [0.5, 0.0, 0.3], atol=5e-3)
    key = model.key(CFG.home_key)
    assert key.ctrl[model.actuator(CFG.gripper_actuator).id] == CFG.gripper_open


def test_zero_pose_matches_the_ur5e_geometry(model):
    T = tool_pose(model, np.zeros(model.nq))
    # At zero the UR5e lies stretched along -x; the wrist offsets d4, d6 (+ tool) go along -y.
    assert np.allclose(T[:3, 3], [-0.425 - 0.3922, -(0.1333 + 0.0996 + TOOL_OFFSET), 0.1625 - 0.0997], atol=1e-6)
    assert np.allclose(T[:3, 2], [0, -1, 0], atol=1e-9)
    assert np.allclose(T, dh_T_base_tool(np.zeros(6)), atol=1e-9)


def test_forward_kinematics_follow_the_dh_table(model):
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = np.zeros(model.nq)
        q[:6] = rng.uniform(-np.pi, np.pi, 6)
        assert np.allclose(tool_pose(model, q), dh_T_base_tool(q[:6]), atol=1e-6)


def test_gripper_closes_on_nothing_and_opens_to_80_mm(model):
    data = at_home(model)
    gripper = model.actuator(CFG.gripper_actuator).id
    assert pad_gap(model, data) == pytest.approx(CFG.max_opening, abs=2e-3)
    data.ctrl[gripper] = CFG.gripper_closed
    step(model, data, 500)
    assert pad_gap(model, data) < 1e-3
    data.ctrl[gripper] = CFG.gripper_open
    step(model, data, 500)
    assert pad_gap(model, data) == pytest.approx(0.08, abs=2e-3)
    assert warning_counts(data) == {}


def test_arm_attaches_into_a_scene(model):
    scene = arm_scene(part_half_size=[0.02, 0.02, 0.02])
    cfg = CFG.with_prefix("arm/")
    data = mujoco.MjData(scene)
    mujoco.mj_resetDataKeyframe(scene, data, scene.key(cfg.home_key).id)
    mujoco.mj_forward(scene, data)
    # The tool sits where the frame offset puts the standalone home pose.
    T_world_base = np.eye(4)
    T_world_base[:3, :3] = data.xmat[scene.body(cfg.base_body).id].reshape(3, 3)
    T_world_base[:3, 3] = [0.1, -0.2, 0.0]
    T_base_tool = T_world_site(model, at_home(model), CFG.tool_site)
    assert np.allclose(T_world_site(scene, data, cfg.tool_site), T_world_base @ T_base_tool, atol=1e-9)
    step(scene, data, 500)
    assert warning_counts(data) == {}
    assert np.all(np.isfinite(data.qpos))


def test_gripper_holds_a_lifted_part():
    scene = arm_scene(part_half_size=[0.03, 0.02, 0.02])  # 40 mm across the closing axis
    cfg = CFG.with_prefix("arm/")
    ik = ArmIK(scene, cfg)
    data = mujoco.MjData(scene)
    mujoco.mj_resetDataKeyframe(scene, data, scene.key(cfg.home_key).id)
    mujoco.mj_forward(scene, data)
    actuators = [scene.actuator(a).id for a in cfg.arm_actuators]
    qadr = [scene.joint(j).qposadr[0] for j in cfg.arm_joints]
    part = scene.body("part").id

    def move_tool_to(z):
        T = T_world_site(scene, data, cfg.tool_site)
        T[:3, :3] = TOOL_DOWN  # close across the part's 40 mm (world y)
        T[:3, 3] = [0.5, 0.0, z]
        goal = ik.solve(data.qpos.copy(), T).q[qadr]
        start = data.qpos[qadr].copy()
        for i in range(750):  # a joint-space ramp over 1 s, then 0.5 s to settle
            data.ctrl[actuators] = start + min(1.0, (i + 1) / 500) * (goal - start)
            mujoco.mj_step(scene, data)

    move_tool_to(0.02)
    data.ctrl[scene.actuator(cfg.gripper_actuator).id] = cfg.gripper_closed
    step(scene, data, 400)
    move_tool_to(0.25)
    offset = data.xpos[part][2] - T_world_site(scene, data, cfg.tool_site)[2, 3]
    step(scene, data, 500)
    assert data.xpos[part][2] > 0.2
    # Held, not creeping: under 1 mm of slip in 1 s.
    assert abs(data.xpos[part][2] - T_world_site(scene, data, cfg.tool_site)[2, 3] - offset) < 1e-3
    assert warning_counts(data) == {}
