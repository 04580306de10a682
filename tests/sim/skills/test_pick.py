"""One pick-and-place judged on the simulator's truth (sim/skills/pick.py). Headless."""

import numpy as np
import pytest

import sim.skills.pick
from psorr.errors import InvalidInputError
from sim.control.cell import ArmCell
from sim.errors import UnreachableTargetError
from sim.skills.pick import pick_and_place
from sim.world import WorldConfig, build_world


def world_for(parts=("u_channel", "chassis")):
    return build_world(WorldConfig(workpieces=parts), np.random.default_rng(3))


def test_a_wrong_estimate_is_reported_and_not_placed():
    """An estimate 30 mm off across the channel: the error is reported and the truth, not the plan,
    decides placement (the part cannot end up seated)."""
    world = world_for()
    world.reset()
    T = world.body_pose("u_channel").copy()
    T[:3, 3] += T[:3, :3] @ [0.0, 0.03, 0.0]
    pick = pick_and_place(world, "u_channel", T)
    assert pick.pose_error_mm == pytest.approx(30.0, abs=1e-6)
    assert not pick.placed
    T_part = world.body_pose("u_channel")
    assert not (np.linalg.norm(T_part[:3, 3] - world.T_world_fixtures["u_channel"][:3, 3]) < 0.005
                and abs(T_part[2, 3] - world.table_top) < 0.003)


def test_pick_and_place_rejects_an_unknown_part():
    world = world_for()
    with pytest.raises(InvalidInputError, match="unknown part"):
        pick_and_place(world, "bushing", np.eye(4))


def test_a_step_that_cannot_go_on_ends_the_pick_open_handed_saying_why(monkeypatch):
    """The seat turns out unreachable once the part is carried above it: the pick reports the abort with
    the lift it made, and the gripper lets go of the part."""
    def unreachable(*args):
        raise UnreachableTargetError("the seat is out of reach", None)

    world = world_for()
    world.reset()
    cell = ArmCell(world)
    monkeypatch.setattr(sim.skills.pick, "release", unreachable)
    result = pick_and_place(world, "u_channel", world.body_pose("u_channel"), cell)
    assert result.note == "aborted mid-pick: the seat is out of reach"
    assert not result.grasped and not result.placed and result.grasp_name
    assert result.lifted_m >= 0.05  # measured when it gave up: still held up at the transport height
    assert cell.holding is None and cell.data.ctrl[cell.gripper] == world.arm.gripper_open
