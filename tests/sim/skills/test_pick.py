"""One pick-and-place judged on the simulator's truth (sim/skills/pick.py). Headless."""

import numpy as np
import pytest

from psorr.errors import InvalidInputError
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
