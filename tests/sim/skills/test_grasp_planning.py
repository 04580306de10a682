"""Grasp planning from a pose estimate (sim/skills/grasp_planning.py). Headless."""

import numpy as np

from psorr.synthetic.catalog import load_catalog
from sim.control.cell import ArmCell
from sim.skills.grasp_planning import configuration_problem, upright_equivalent
from sim.world import WorldConfig, build_world


def test_a_flipped_but_symmetric_estimate_is_planned_upright():
    info = load_catalog()["transformer"]
    flip = next(S for S in info.symmetries if S[2, 2] < -0.5)  # 180 deg about a horizontal axis
    T_true = np.eye(4)
    T_true[:3, 3] = (0.3, 0.1, 0.75)
    upright = upright_equivalent(T_true @ flip, info)
    assert np.allclose(upright, T_true, atol=1e-9)


def test_plans_refuse_a_wound_up_arm_and_an_arm_in_the_table():
    """The local IK can land on a configuration with the upper arm swung down behind the base: its tool
    pose is right, but the arm could only get there through the table."""
    world = build_world(WorldConfig(workpieces=("u_channel", "chassis")), np.random.default_rng(3))
    cell = ArmCell(world)
    home = world.data.qpos.copy()
    assert configuration_problem(cell, home) == ""
    wound = home.copy()
    wound[cell.qadr[1]] = -3.87
    assert "wound-up" in configuration_problem(cell, wound)
    into_table = home.copy()
    into_table[cell.qadr[1]] = -0.2  # the upper arm nearly level: the forearm hangs through the table
    into_table[cell.qadr[2]] = 1.0
    assert "under the table" in configuration_problem(cell, into_table)
    elbow_on_table = home.copy()
    elbow_on_table[cell.qadr[1]] = -0.1  # the upper arm level, the forearm folded back up: the elbow is in the top
    elbow_on_table[cell.qadr[2]] = 2.8
    assert "touch table" in configuration_problem(cell, elbow_on_table)


def test_the_grasp_approached_straight_down_is_planned_before_a_tilted_one_listed_first():
    """A part lying any way has grasps for each rest; another rest's grasp, tilted 30 degrees here, is
    listed first but must not be taken while the rest's own grasp, straight down, is reachable."""
    import dataclasses
    from types import MappingProxyType

    from sim.parts.grasp import Grasp
    from sim.skills.grasp_planning import plan_grasp

    world = build_world(WorldConfig(workpieces=("u_channel", "chassis")), np.random.default_rng(3))
    tilt = np.radians(30.0)
    tilted = Grasp("other_rest", [0.0, 0.0, 0.02], [np.sin(tilt), 0.0, -np.cos(tilt)], [0.0, 1.0, 0.0], 0.05)
    upright = Grasp("this_rest", [0.0, 0.0, 0.02], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], 0.05)
    world = dataclasses.replace(world, grasps=MappingProxyType({**world.grasps, "u_channel": (tilted, upright)}))
    plan = plan_grasp(ArmCell(world), "u_channel", world.T_world_workpieces["u_channel"])
    assert plan.grasp.name == "this_rest"
