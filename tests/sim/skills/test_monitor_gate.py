"""The safety monitor skips its render while nothing could intrude (sim/skills/monitor_gate.py), and
counts what the render would have counted."""

import mujoco
import numpy as np
import pytest

from sim.control.ik import T_world_site
from sim.skills.perception import Perception
from sim.world import WorldConfig, build_world

PARTS = ("u_channel", "transformer")


@pytest.fixture(scope="module")
def world():
    return build_world(WorldConfig(workpieces=PARTS), np.random.default_rng(7))


@pytest.fixture
def perception(world):
    with Perception(world, np.random.default_rng(0), recognize=False) as p:
        yield p


class _Always:
    def may_intrude(self, *args) -> bool:
        return True


def _counting_renders(perception) -> list:
    calls, render = [], perception._monitor.render
    perception._monitor.render = lambda data: calls.append(data.time) or render(data)
    return calls


def test_nobody_near_the_table_is_zero_without_a_render(world, perception):
    renders = _counting_renders(perception)
    data = world.reset(mujoco.MjData(world.model))  # the arm at home hangs over the table; the person stands back
    assert perception.monitor_intruding(data) == 0
    assert renders == []


def test_through_a_whole_reach_the_gated_count_is_the_rendered_count(world):
    """Where the gate skips, the render would have counted 0."""
    with Perception(world, np.random.default_rng(0), recognize=False) as gated, \
            Perception(world, np.random.default_rng(0), recognize=False) as rendered:
        rendered._gate = _Always()
        data = world.reset(mujoco.MjData(world.model))
        skipped = 0
        for t in np.linspace(0.0, 2 * world.occluder.peak_s[0], 40):
            world.apply_occluder(data, t)
            mujoco.mj_forward(world.model, data)
            renders = _counting_renders(gated)
            expected, got = rendered.monitor_intruding(data), gated.monitor_intruding(data)
            if renders:  # the two draw different noise once one has skipped: the same verdict, not the same count
                assert (got > 0) == (expected > 0)
            else:
                skipped += 1
                assert expected == 0
            del gated._monitor.render
        assert 0 < skipped < 40  # the person both stood back and reached in


def test_a_held_part_is_skipped_but_a_loose_one_over_the_table_is_not(world, perception):
    data = world.reset(mujoco.MjData(world.model))
    tool = T_world_site(world.model, data, world.arm.tool_site)
    part = world.model.body("u_channel")
    qadr = world.model.jnt_qposadr[part.jntadr[0]]
    data.qpos[qadr:qadr + 3] = tool[:3, 3] - [0.0, 0.0, 0.05]  # hanging just under the tool, above the ceiling
    mujoco.mj_forward(world.model, data)
    renders = _counting_renders(perception)
    assert perception.monitor_intruding(data, holding="u_channel") == 0 and renders == []
    assert perception.monitor_intruding(data) > 0 and len(renders) == 1
