"""Pick-and-place episodes in the simulated cell (sim/episode.py). Headless."""

import math

import numpy as np
import pytest

import sim.episode as episode
from psorr.errors import InvalidInputError
from sim.episode import EpisodeResult, PickResult, run_episode
from sim.world import WorldConfig, build_world

PARTS = ("u_channel", "chassis")
SEED = 3


def world_for(seed=SEED, parts=PARTS):
    return build_world(WorldConfig(workpieces=parts), np.random.default_rng(seed))


def same(a: PickResult, b: PickResult) -> bool:
    """Field-wise equality where nan equals nan."""
    for x, y in zip(a.__dict__.values(), b.__dict__.values()):
        if isinstance(x, float) and math.isnan(x):
            if not (isinstance(y, float) and math.isnan(y)):
                return False
        elif x != y:
            return False
    return True


@pytest.fixture(scope="module")
def oracle():
    world = world_for()
    return world, run_episode(world, np.random.default_rng(SEED), poses="oracle")


def test_oracle_episode_picks_and_places_every_part(oracle):
    world, result = oracle
    assert isinstance(result, EpisodeResult) and result.wall_s > 0
    assert [p.part for p in result.picks] == list(PARTS)
    for pick in result.picks:
        assert pick.grasp_name, pick.note
        assert pick.grasped and pick.lifted_m >= 0.05, pick.note
        assert pick.placed, pick.note
        assert pick.place_error_mm <= 5.0 and pick.place_error_deg <= 3.0
        assert pick.pose_error_mm == pytest.approx(0.0, abs=1e-3) and pick.rot_error_deg < 1e-3


def test_oracle_placement_is_true_in_the_simulator(oracle):
    """Re-check the seating independently of PickResult: each part's body sits in its fixture."""
    world, _ = oracle
    for name in PARTS:
        T, F = world.body_pose(name), world.T_world_fixtures[name]
        assert np.linalg.norm(T[:3, 3] - F[:3, 3]) < 0.005
        assert abs(T[2, 3] - world.table_top) < 0.003
        assert T[2, 2] > math.cos(math.radians(3))  # upright
        R = F[:3, :3].T @ T[:3, :3]
        yaw = math.degrees(math.atan2(R[1, 0], R[0, 0]))
        symmetric = len(world.catalog[name].symmetries) > 1
        assert min(abs(yaw), 180 - abs(yaw)) < 3 if symmetric else abs(yaw) < 3


def test_same_seed_gives_the_same_picks(oracle):
    _, first = oracle
    again = run_episode(world_for(), np.random.default_rng(SEED), poses="oracle")
    assert len(again.picks) == len(first.picks)
    assert all(same(a, b) for a, b in zip(first.picks, again.picks))


def test_recognized_episode_picks_only_recognised_poses(monkeypatch):
    """Every grasp is planned on a pose the latest look returned (a grasp on any other pose is a bug)."""
    from sim.perception import Perception

    looks, picked = [], []
    real_look, real_pick = Perception.look, episode.pick_and_place

    def spy_look(self, data, holding=None):
        look = real_look(self, data, holding)
        looks.append(look)
        return look

    def spy_pick(world, part, T_est, cell=None, alternatives=(), perception=None):
        picked.append((part, np.array(T_est), looks[-1]))
        return real_pick(world, part, T_est, cell, alternatives, perception)

    monkeypatch.setattr(Perception, "look", spy_look)
    monkeypatch.setattr(episode, "pick_and_place", spy_pick)
    result = run_episode(world_for(), np.random.default_rng(SEED), poses="recognized")

    assert sorted(p.part for p in result.picks) == sorted(PARTS)
    assert result.looks == len(looks) >= 1
    for part, T_est, look in picked:
        assert any(np.array_equal(T_est, e.T_world_part) for e in look.estimates[part])
    for pick in result.picks:
        if pick.part in [part for part, _, _ in picked]:
            assert math.isfinite(pick.pose_error_mm) and math.isfinite(pick.rot_error_deg)
            if pick.grasped:
                assert pick.lifted_m >= 0.05
        else:
            assert not pick.grasped and not pick.placed and pick.grasp_name == ""
            assert pick.note.startswith("not recognised")


def test_run_episode_rejects_an_unknown_mode():
    with pytest.raises(InvalidInputError, match="oracle"):
        run_episode(world_for(), np.random.default_rng(0), poses="guess")


def test_a_wrong_estimate_is_reported_and_not_placed():
    """An estimate 30 mm off across the channel: the error is reported and the truth, not the plan,
    decides placement (the part cannot end up seated)."""
    world = world_for()
    world.reset()
    T = world.body_pose("u_channel").copy()
    T[:3, 3] += T[:3, :3] @ [0.0, 0.03, 0.0]
    pick = episode.pick_and_place(world, "u_channel", T)
    assert pick.pose_error_mm == pytest.approx(30.0, abs=1e-6)
    assert not pick.placed
    T_part = world.body_pose("u_channel")
    assert not (np.linalg.norm(T_part[:3, 3] - world.T_world_fixtures["u_channel"][:3, 3]) < 0.005
                and abs(T_part[2, 3] - world.table_top) < 0.003)


def test_pick_and_place_rejects_an_unknown_part():
    world = world_for()
    with pytest.raises(InvalidInputError, match="unknown part"):
        episode.pick_and_place(world, "bushing", np.eye(4))


def test_a_flipped_but_symmetric_estimate_is_planned_upright():
    from psorr.synthetic.catalog import load_catalog
    from sim.grasp_planning import upright_equivalent

    info = load_catalog()["transformer"]
    flip = next(S for S in info.symmetries if S[2, 2] < -0.5)  # 180 deg about a horizontal axis
    T_true = np.eye(4)
    T_true[:3, 3] = (0.3, 0.1, 0.75)
    upright = upright_equivalent(T_true @ flip, info)
    assert np.allclose(upright, T_true, atol=1e-9)


def test_plans_refuse_a_wound_up_arm_and_an_arm_in_the_table():
    """The local IK can land on a configuration with the upper arm swung down behind the base: its tool
    pose is right, but the arm could only get there through the table."""
    from sim.cell import ArmCell
    from sim.grasp_planning import configuration_problem

    world = world_for()
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
