"""psorr/PickPlace-v1, the plan-level env (sim/plans/env.py). Headless, oracle poses for speed."""

import warnings
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import sim  # noqa: F401  (registers the envs)
from sim.plans.env import COLOURS, PLACE_REWARD, WRONG_REWARD, PlanPickPlaceEnv

REPO = Path(__file__).resolve().parents[3]
PLAN = REPO / "tasks" / "plans" / "red_hub.yaml"


def test_check_env_passes_without_warnings():
    env = gymnasium.make("psorr/PickPlace-v1", plan=PLAN, poses="oracle", occluder=False, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    env.close()
    assert not [w for w in caught if "gymnasium" in str(w.filename)], [str(w.message) for w in caught]


def _slot(obs, env, part, colour="any"):
    for slot in np.flatnonzero(obs["valid"]):
        if env.models[obs["model"][slot]] == part and colour in ("any", COLOURS[obs["colour"][slot]]):
            return int(slot)
    pytest.fail(f"no {colour} {part} in the observation")


@pytest.fixture
def env():
    env = PlanPickPlaceEnv(PLAN, poses="oracle", occluder=False)
    yield env
    env.close()


def test_the_red_hub_in_its_named_fixture_reaches_the_goal(env):
    obs, info = env.reset(seed=0)
    assert env.destinations == ("fixture", "tote", "fixture_b")
    assert info["goal_left"] == [("hub", "red", "fixture_b")] and not info["is_success"]
    obs, reward, terminated, truncated, info = env.step([_slot(obs, env, "hub", "red"), 2])
    assert reward == PLACE_REWARD and terminated and not truncated and info["is_success"]
    # one of the three fixtures (the hubs' and the transformer's) filled, none of the tote, and fixture_b
    assert obs["occupancy"].tolist() == pytest.approx([1 / 3, 0.0, 1.0])


def test_the_blue_twin_is_not_what_the_goal_wants_and_fills_the_fixture(env):
    obs, _ = env.reset(seed=0)
    obs, reward, terminated, _, info = env.step([_slot(obs, env, "hub", "blue"), 2])
    assert reward == WRONG_REWARD and not terminated and info["goal_left"] == [("hub", "red", "fixture_b")]
    red = _slot(obs, env, "hub", "red")
    assert info["action_mask"][red, 2] == 0
    _, reward, _, _, info = env.step([red, 2])
    assert reward < 0 and "fixture_b is occupied" in info["refused"]


def test_a_move_the_mask_forbids_is_refused_without_moving():
    env = PlanPickPlaceEnv(PLAN, poses="oracle", occluder=False, max_objects=5)
    obs, info = env.reset(seed=0)
    slot = _slot(obs, env, "hub", "red")
    assert info["action_mask"][slot].tolist() == [0, 0, 1]  # hubs go to fixtures, and this plan names theirs
    time = info["sim_time"]
    _, reward, _, _, info = env.step([slot, env.destinations.index("tote")])
    assert reward < 0 and "puts hub in fixture" in info["refused"] and info["sim_time"] == time
    _, _, _, _, info = env.step([slot, env.destinations.index("fixture")])
    assert "the plan names the hub fixtures" in info["refused"] and info["sim_time"] == time
    transformer = _slot(obs, env, "transformer")
    _, _, _, _, info = env.step([transformer, 2])
    assert "fixture_b is a fixture for hub, not for transformer" in info["refused"]
    empty = env.max_objects - 1
    _, _, _, _, info = env.step([empty, 0])
    assert "holds no detection" in info["refused"]
    env.close()


def test_depth_array_renders_the_looks_depth_or_the_cell_now():
    from gymnasium.utils.passive_env_checker import env_render_passive_checker

    seen = PlanPickPlaceEnv(PLAN, poses="recognized", occluder=False, render_mode="depth_array")
    obs, _ = seen.reset(seed=0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        depth = env_render_passive_checker(seen)
    assert not caught, [str(w.message) for w in caught]
    assert depth.dtype == np.float32 and np.array_equal(depth, obs["depth"])  # the Kinect's, noise and all
    seen.close()
    true = PlanPickPlaceEnv(PLAN, poses="oracle", occluder=False, render_mode="depth_array")
    obs, _ = true.reset(seed=0)
    depth = true.render()
    assert not obs["depth"].any()  # an oracle look takes no picture: the cell is rendered now
    assert depth.shape == obs["depth"].shape and depth.dtype == np.float32
    assert 0.5 < float(np.median(depth)) < 1.5  # metres: the table, as far as the camera stands
    true.close()


def test_the_env_runs_vectorised_in_both_modes_and_they_agree():
    """gymnasium.make_vec, sync and async (worker processes): the same seeds give the same observations."""
    seen = {}
    for mode in ("sync", "async"):
        envs = gymnasium.make_vec("psorr/PickPlace-v1", num_envs=2, vectorization_mode=mode, plan=PLAN,
                                  poses="oracle", occluder=False)
        obs, _ = envs.reset(seed=0)
        wait = np.array([[envs.single_action_space.nvec[0] - 1, 0]] * 2)
        obs, reward, terminated, truncated, info = envs.step(wait)
        envs.close()
        assert reward.tolist() == [-0.01, -0.01] and not terminated.any() and not info["is_success"].any()
        seen[mode] = obs
    for key in seen["sync"]:
        assert np.array_equal(seen["sync"][key], seen["async"][key]), key


def test_the_same_seed_gives_the_same_episode_bit_for_bit():
    """Recognised poses and the person about: two envs, one seed, the same moves, the same everything."""
    runs = []
    for _ in range(2):
        env = PlanPickPlaceEnv(PLAN, poses="recognized", occluder=True)
        obs, info = env.reset(seed=4)
        steps = [(obs, 0.0, info["sim_time"])]
        for _ in range(2):
            red = [s for s in np.flatnonzero(obs["valid"]) if env.models[obs["model"][s]] == "hub"
                   and COLOURS[obs["colour"][s]] == "red"]
            action = [red[0], 2] if red and info["action_mask"][red[0], 2] else [env.max_objects, 0]
            obs, reward, terminated, truncated, info = env.step(action)
            steps.append((obs, reward, info["sim_time"]))
            if terminated or truncated:
                break
        env.close()
        runs.append(steps)
    assert len(runs[0]) == len(runs[1])
    for (obs_a, reward_a, time_a), (obs_b, reward_b, time_b) in zip(*runs):
        assert reward_a == reward_b and time_a == time_b
        for key in obs_a:
            assert np.array_equal(obs_a[key], obs_b[key], equal_nan=True), key
