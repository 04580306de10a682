"""The arm's differential IK with mink (sim/control/ik.py): reaching, refusing, keeping clear. Headless."""

import numpy as np
import pytest
from arm_scenes import CFG, TOOL_DOWN, arm_scene, tool_pose

from psorr.errors import InvalidInputError, PsorrError
from sim.control.ik import ArmIK
from sim.errors import UnreachableTargetError
from sim.world.robot import load_arm_spec


@pytest.fixture(scope="module")
def model():
    return load_arm_spec().compile()


@pytest.fixture(scope="module")
def ik(model):
    return ArmIK(model, CFG)


def test_ik_reaches_seeded_targets(model, ik):
    rng = np.random.default_rng(11)
    home = model.key(CFG.home_key).qpos
    lo, hi = model.jnt_range.T
    for _ in range(5):
        yaw = rng.uniform(-np.pi / 2, np.pi / 2)
        T = np.eye(4)
        T[:3, :3] = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]]) @ TOOL_DOWN
        T[:3, 3] = rng.uniform([0.3, -0.3, 0.05], [0.6, 0.3, 0.4])
        result = ik.solve(home, T)
        assert result.converged
        reached = tool_pose(model, result.q)  # checked by FK, not by the solver's word
        assert np.linalg.norm(reached[:3, 3] - T[:3, 3]) < 1e-3
        assert np.degrees(np.arccos(np.clip((np.trace(reached[:3, :3].T @ T[:3, :3]) - 1) / 2, -1, 1))) < 1.0
        assert np.all(result.q >= lo) and np.all(result.q <= hi)
        assert np.array_equal(result.q[6:], home[6:])  # fingers untouched
        assert not result.q.flags.writeable


def test_ik_raises_on_unreachable_target(model, ik):
    T = np.eye(4)
    T[:3, :3] = TOOL_DOWN
    T[:3, 3] = [2.0, 0.0, 0.3]
    with pytest.raises(PsorrError, match=r"\(2\.000, 0\.000, 0\.300\) m is unreachable.* mm and .* deg away") as info:
        ik.solve(model.key(CFG.home_key).qpos, T)
    assert isinstance(info.value, UnreachableTargetError)
    assert info.value.result.pos_error > 0.5
    result = ik.solve(model.key(CFG.home_key).qpos, T, raise_on_failure=False)
    assert not result.converged


def test_ik_rejects_bad_inputs(model, ik):
    home = model.key(CFG.home_key).qpos
    T = tool_pose(model, home)
    with pytest.raises(InvalidInputError, match="q_start"):
        ik.solve(home[:6], T)
    with pytest.raises(InvalidInputError, match="orthonormal"):
        ik.solve(home, np.diag([2.0, 1.0, 1.0, 1.0]))
    with pytest.raises(InvalidInputError, match="no_such_geom"):
        ik.solve(home, T, collision_geoms=[(CFG.pad_geoms, ["no_such_geom"])])
    with pytest.raises(InvalidInputError, match="prefix"):
        ArmIK(model, CFG.with_prefix("arm/"))


def test_ik_in_a_scene_keeps_pads_off_the_floor():
    scene = arm_scene()
    cfg = CFG.with_prefix("arm/")
    ik = ArmIK(scene, cfg)
    q_home = scene.key(cfg.home_key).qpos
    T = tool_pose(scene, q_home, cfg)
    T[:3, 3] = [0.45, -0.1, 0.005]  # pads would reach 12 mm into the floor
    assert ik.solve(q_home, T).converged
    with pytest.raises(UnreachableTargetError):
        ik.solve(q_home, T, collision_geoms=[(cfg.pad_geoms, ["floor"])])
    T[2, 3] = 0.03
    result = ik.solve(q_home, T, collision_geoms=[(cfg.collision_geoms, ["floor"])])
    assert result.converged and result.pos_error < 1e-3
