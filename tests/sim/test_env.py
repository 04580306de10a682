"""The gymnasium env for task-level planners (sim/env.py). Headless; oracle poses keep it fast (~1 s per pick)."""

import importlib
import warnings
from types import MappingProxyType

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from paths import REPO

import sim
from psorr.errors import InvalidInputError
from sim.env import DEFAULT_MAX_STEPS, REFUSED_REWARD, WAIT_REWARD, PickPlaceEnv
from sim.episode import Episode
from sim.skills.perception import MONITOR_OCCUPIED, Estimate, Look
from sim.world import WorldConfig
from sim.world.tasks import load_task

PARTS = ("u_channel", "chassis")
CONFIG = WorldConfig(workpieces=PARTS, occluder=False)
SEED = 3
WAIT = len(PARTS)


def make(**kwargs) -> PickPlaceEnv:
    return PickPlaceEnv(**{"task": CONFIG, "poses": "oracle", "occluder": False, **kwargs})


def state(env: PickPlaceEnv) -> tuple:
    data = env.unwrapped.world.data
    return data.time, data.qpos.copy(), data.qvel.copy(), data.ctrl.copy(), data.mocap_pos.copy()


def test_check_env_passes_without_warnings():
    env = gymnasium.make("psorr/PickPlace-v0", task=CONFIG, poses="oracle", occluder=False,
                         render_mode="rgb_array", max_steps=10)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    assert [str(w.message) for w in caught] == []
    obs, _ = env.reset(seed=SEED)
    assert env.render().shape == (480, 640, 3)
    assert obs["depth"].shape == (480, 640) and not obs["depth"].any()  # oracle looks take no picture
    env.close()
    env.close()


def test_make_and_registration():
    importlib.reload(sim)  # a second registration must neither raise nor warn
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        importlib.reload(sim)
    env = gymnasium.make("psorr/PickPlace-v0", task=CONFIG, poses="oracle", occluder=False)
    assert isinstance(env.unwrapped, PickPlaceEnv)
    assert env.action_space == gymnasium.spaces.Discrete(len(PARTS) + 1)
    obs, info = env.reset(seed=SEED)
    assert obs in env.observation_space
    assert obs["seen"].tolist() == [1, 1] and obs["scores"].tolist() == [1.0, 1.0]
    assert info["action_mask"].tolist() == [1, 1, 1] and info["pick"] is None
    env.close()


def test_the_default_task_is_the_demo_task_file(tmp_path, monkeypatch):
    # An installed psorr has no tasks/ folder: the env's default is the WorldConfig that tasks/demo.yaml spells out.
    assert load_task(REPO / "tasks" / "demo.yaml").world == WorldConfig()
    monkeypatch.chdir(tmp_path)
    env = PickPlaceEnv()
    assert env.parts == ("u_channel", "chassis", "transformer", "flanged_hub")
    assert env.observation_space["poses"].shape == (4, 7) and env.action_space.n == 5


def test_a_relative_task_path_is_taken_from_the_working_directory(tmp_path, monkeypatch):
    (tmp_path / "tasks").mkdir()
    (tmp_path / "tasks" / "two.yaml").write_text("workpieces: [bracket, bushing]\n")
    monkeypatch.chdir(tmp_path)
    assert PickPlaceEnv(task="tasks/two.yaml").parts == ("bracket", "bushing")


@pytest.mark.parametrize("kwargs, names", [
    ({"poses": "guess"}, "oracle"), ({"render_mode": "human"}, "rgb_array"),
    ({"task": 42}, "WorldConfig"), ({"max_steps": 0}, "positive"),
])
def test_bad_arguments_name_the_valid_choices(kwargs, names):
    with pytest.raises(InvalidInputError, match=names):
        make(**kwargs)


def test_same_seed_gives_the_same_observations_and_rewards():
    runs = []
    for _ in range(2):
        env = make()
        obs, _ = env.reset(seed=SEED)
        steps = [(obs, 0.0)]
        for action in (WAIT, 0):
            obs, reward, *_ = env.step(action)
            steps.append((obs, reward))
        runs.append((steps, env.episode.picks[0]))
        env.close()
    (first, pick_a), (again, pick_b) = runs
    assert pick_a == pick_b and pick_a.placed
    for (obs_a, r_a), (obs_b, r_b) in zip(first, again):
        assert r_a == r_b
        assert obs_a.keys() == obs_b.keys() and all(np.array_equal(obs_a[k], obs_b[k]) for k in obs_a)
    assert [r for _, r in first] == [0.0, WAIT_REWARD, 2.0]


def blind_to(part: str | None):
    """A look that did not return ``part`` (None: a look that found someone reaching in)."""
    real = Episode.look

    def look(self):
        seen = real(self)
        if part is None:
            return Look(seen.frame, (), MappingProxyType({}), 5000, True)
        kept = {p: e for p, e in seen.estimates.items() if p != part}
        return Look(seen.frame, seen.detections, MappingProxyType(kept), seen.intruding, seen.occupied)

    return look


@pytest.mark.parametrize("hidden, why", [("chassis", "no pose of chassis"), (None, "reaching over the table")])
def test_a_pick_the_latest_look_does_not_allow_is_refused_without_moving(monkeypatch, hidden, why):
    monkeypatch.setattr(Episode, "look", blind_to(hidden))
    env = make()
    obs, info = env.reset(seed=SEED)
    part = PARTS.index(hidden or "chassis")
    assert obs["seen"][part] == 0 and info["action_mask"][part] == 0
    before = state(env)
    obs_after, reward, terminated, truncated, info = env.step(part)
    after = state(env)
    assert why in info["refused"] and info["pick"] is None
    assert reward == REFUSED_REWARD and not terminated and not truncated
    assert before[0] == after[0] and all(np.array_equal(a, b) for a, b in zip(before[1:], after[1:]))
    assert all(np.array_equal(obs[k], obs_after[k]) for k in obs)
    assert env.episode.picks == [] and env.episode.remaining == list(PARTS)
    env.close()


def test_an_oracle_run_picks_every_part_from_the_latest_look(monkeypatch):
    """Picks only use a pose the latest look returned; a second pick of a part is refused."""
    latest, picked = [], []
    real_look, real_pick = Episode.look, Episode.pick

    def spy_look(self):
        latest[:] = [real_look(self)]
        return latest[0]

    def spy_pick(self, part, T, looks=1, alternatives=()):
        picked.append(any(e.T_world_part is T for e in latest[0].estimates[part]))
        return real_pick(self, part, T, looks, alternatives)

    monkeypatch.setattr(Episode, "look", spy_look)
    monkeypatch.setattr(Episode, "pick", spy_pick)
    env = make()
    env.reset(seed=SEED)
    total, outcomes = 0.0, []
    for action in (0, 0, 1):
        obs, reward, terminated, truncated, info = env.step(action)
        total += reward
        outcomes.append((terminated, truncated, info["refused"]))
    assert picked == [True, True]
    assert outcomes[1] == (False, False, "u_channel was picked already")
    assert outcomes[2][:2] == (True, False)
    assert total == pytest.approx(4.0 + REFUSED_REWARD)
    assert obs["done"].tolist() == [1, 1] and obs["seen"].tolist() == [0, 0]
    assert all(p.grasped and p.placed for p in env.episode.result().picks)
    env.close()


def test_max_steps_truncates_and_gives_the_rest_up():
    env = make(max_steps=2)
    env.reset(seed=SEED)
    assert env.step(WAIT)[3] is False
    _, _, terminated, truncated, info = env.step(WAIT)
    assert (terminated, truncated) == (False, True) and "2 steps" in info["gave_up"]
    assert [p.note for p in env.episode.result().picks] == [info["gave_up"]] * len(PARTS)
    env.close()


def test_a_placed_part_that_recognition_still_finds_is_not_seen(monkeypatch):
    # Recognition finds a placed part in its fixture; it is done, so it has no pose to pick from.
    real = Episode.look

    def sees_everything(self):
        seen = real(self)
        every = {p: (Estimate(self.world.body_pose(p), 0.8),) for p in PARTS}
        return Look(seen.frame, seen.detections, MappingProxyType(every), seen.intruding, seen.occupied)

    monkeypatch.setattr(Episode, "look", sees_everything)
    env = make()
    env.reset(seed=SEED)
    obs, *_, info = env.step(0)
    assert obs["done"].tolist() == [1, 0] and obs["seen"].tolist() == [0, 1]
    assert obs["scores"][0] == 0 and not obs["poses"][0].any() and info["action_mask"].tolist() == [0, 1, 1]
    env.close()


def test_make_sets_the_step_limit_as_for_any_gymnasium_env():
    assert gymnasium.spec("psorr/PickPlace-v0").max_episode_steps == DEFAULT_MAX_STEPS
    env = gymnasium.make("psorr/PickPlace-v0", task=CONFIG, poses="oracle", occluder=False, max_episode_steps=2)
    assert env.unwrapped.max_steps is None  # the TimeLimit counts, so that max_episode_steps is obeyed
    env.reset(seed=SEED)
    assert env.step(WAIT)[3] is False
    assert env.step(WAIT)[3] is True
    assert [p.note for p in env.unwrapped.episode.result().picks] == ["the episode ended before its pick"] * 2
    env.close()


def test_an_oracle_look_reports_the_monitor_count_that_made_it_occupied():
    env = make(task=WorldConfig(workpieces=PARTS, occluder=True), occluder=True)
    _, info = env.reset(seed=0)
    occupied = []
    for _ in range(12):
        obs, *_, info = env.step(WAIT)
        occupied.append(bool(obs["occupied"][0]))
        assert (info["intruding"] >= MONITOR_OCCUPIED) == occupied[-1]
    assert any(occupied) and not all(occupied)  # the person reached in, and withdrew, within these looks
    env.close()
