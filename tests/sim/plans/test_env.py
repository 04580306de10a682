"""psorr/PickPlace-v1, the plan-level env (sim/plans/env.py). Headless, oracle poses for speed."""

import warnings
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import sim  # noqa: F401  (registers the envs)
from sim.plans.env import COLOURS, DESTINATIONS, PLACE_REWARD, WRONG_REWARD, PlanPickPlaceEnv

REPO = Path(__file__).resolve().parents[3]
PLAN = REPO / "tasks" / "plans" / "red_hub.yaml"


def test_check_env_passes_without_warnings():
    env = gymnasium.make("psorr/PickPlace-v1", plan=PLAN, poses="oracle", occluder=False, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    env.close()
    assert not [w for w in caught if "gymnasium" in str(w.filename)], [str(w.message) for w in caught]


def _slot(obs, env, part, colour):
    for slot in np.flatnonzero(obs["valid"]):
        if env.models[obs["model"][slot]] == part and COLOURS[obs["colour"][slot]] == colour:
            return int(slot)
    pytest.fail(f"no {colour} {part} in the observation")


@pytest.fixture
def env():
    env = PlanPickPlaceEnv(PLAN, poses="oracle", occluder=False)
    yield env
    env.close()


def test_the_red_hub_in_its_fixture_reaches_the_goal(env):
    obs, info = env.reset(seed=0)
    assert info["goal_left"] == [("hub", "red", "fixture")] and not info["is_success"]
    obs, reward, terminated, truncated, info = env.step([_slot(obs, env, "hub", "red"), 0])
    assert reward == PLACE_REWARD and terminated and not truncated and info["is_success"]
    assert obs["occupancy"][DESTINATIONS.index("fixture")] > 0


def test_the_blue_twin_is_not_what_the_goal_wants(env):
    obs, _ = env.reset(seed=0)
    obs, reward, terminated, _, info = env.step([_slot(obs, env, "hub", "blue"), 0])
    assert reward == WRONG_REWARD and not terminated and info["goal_left"] == [("hub", "red", "fixture")]


def test_a_move_the_mask_forbids_is_refused_without_moving():
    env = PlanPickPlaceEnv(PLAN, poses="oracle", occluder=False, max_objects=5)
    obs, info = env.reset(seed=0)
    slot = _slot(obs, env, "hub", "red")
    assert info["action_mask"][slot, DESTINATIONS.index("tote")] == 0  # the cell puts hubs in fixtures
    time = info["sim_time"]
    _, reward, _, _, info = env.step([slot, DESTINATIONS.index("tote")])
    assert reward < 0 and "puts hub in fixture" in info["refused"] and info["sim_time"] == time
    empty = env.max_objects - 1
    _, _, _, _, info = env.step([empty, 0])
    assert "holds no detection" in info["refused"]
    env.close()
