"""The robot's perception in the cell (sim/skills/perception.py), the reaching person (sim/people/occluder.py
ReachingHuman) and how episodes react to them (sim/episode.py). Headless."""

import contextlib
import math

import mujoco
import numpy as np
import pytest

import sim.episode as episode
from sim.skills.perception import Look, Perception
from sim.world import WorldConfig, build_world

SEED = 7
PARTS = ("u_channel", "transformer")


@pytest.fixture(scope="module")
def world():
    return build_world(WorldConfig(workpieces=PARTS), np.random.default_rng(SEED))


@pytest.fixture(scope="module")
def perception(world):
    with Perception(world, np.random.default_rng(0), recognize=False) as p:
        yield p


def at_peak(world, data=None):
    """``data`` with the person's hand over the table at the peak of the world's sampled reach."""
    data = world.reset(mujoco.MjData(world.model) if data is None else data)
    world.apply_occluder(data, world.occluder.peak_s[0])
    mujoco.mj_forward(world.model, data)
    return data


def test_nobody_reaching_in_is_not_occupied_although_the_arm_hangs_over_the_table(world, perception):
    data = world.reset(mujoco.MjData(world.model))
    # At home the arm's links are over the table, above the ceiling: the self-filter removes them.
    look = perception.look(data)
    assert not look.occupied and look.intruding < 50
    assert not perception.occupied(data)


def test_a_person_reaching_in_is_seen_by_the_look_and_by_the_monitor(world, perception):
    data = at_peak(world)
    look = perception.look(data)
    assert look.occupied and look.intruding > 1000
    assert look.detections == () and dict(look.estimates) == {}  # nothing is recognised while someone reaches in
    assert perception.occupied(data)


def test_the_part_in_the_hand_is_not_an_intrusion(world, perception):
    """A part held high by the tool is above the ceiling; it is the robot's, so it does not count."""
    data = world.reset(mujoco.MjData(world.model))
    from sim.control.ik import T_world_site

    tool = T_world_site(world.model, data, world.arm.tool_site)
    part = world.model.body("u_channel")
    qadr = world.model.jnt_qposadr[part.jntadr[0]]
    data.qpos[qadr:qadr + 3] = tool[:3, 3] - [0.0, 0.0, 0.05]  # hanging just under the tool
    mujoco.mj_forward(world.model, data)
    assert perception.look(data).intruding > 200
    assert perception.look(data, holding="u_channel").intruding < 50


@contextlib.contextmanager
def _recognizer_calls(perception):
    """The (cloud, known) of each call the looks make to PSORR, while in the block."""
    calls, recognize = [], perception._recognizer.recognize
    perception._recognizer.recognize = lambda cloud, rng, known=(), observer=None: calls.append(
        (cloud, known)) or recognize(cloud, rng, known=known, observer=observer)
    try:
        yield calls
    finally:
        del perception._recognizer.recognize  # the recognizer is shared: back to its class's method


def test_the_recognizer_sees_only_the_workspace(world):
    """PSORR gets the cloud cropped to the table (less the arm and the fixtures, which the robot knows):
    the person standing beyond the edge is not in it, and every estimate it returns is of a task part."""
    with Perception(world, np.random.default_rng(1)) as p, _recognizer_calls(p) as calls:
        look = p.look(world.reset(mujoco.MjData(world.model)))
    body = look.frame.segmentation.ravel()
    kept = np.isfinite(calls[0][0].points).all(axis=1)
    fixtures = [world.model.body(f"{name}_fixture").id for name in PARTS]
    assert np.isin(body, fixtures).sum() > 500 and not kept[np.isin(body, fixtures)].any()
    parts = [world.model.body(name).id for name in PARTS]
    assert kept[np.isin(body, parts)].mean() > 0.95
    assert not look.occupied
    assert set(look.estimates) <= set(PARTS)
    for estimates in look.estimates.values():
        scores = [e.score for e in estimates]
        assert scores == sorted(scores, reverse=True)


def test_a_look_again_follows_the_parts_the_last_look_found(world):
    """The camera stands still: the second look hands PSORR the first look's detections to follow, and
    finds the same parts where they were."""
    with Perception(world, np.random.default_rng(1)) as p, _recognizer_calls(p) as calls:
        data = world.reset(mujoco.MjData(world.model))
        first, second = p.look(data), p.look(data)
    assert calls[0][1] == () and calls[1][1] == first.detections
    assert sorted(first.estimates) == sorted(second.estimates)
    for part, estimates in first.estimates.items():
        moved = np.linalg.norm(estimates[0].T_world_part[:3, 3] - second.estimates[part][0].T_world_part[:3, 3])
        assert moved < 0.002, part


# ---------------------------------------------------------------------------------------------- episodes

def test_the_robot_waits_while_someone_reaches_in_then_picks(world, monkeypatch):
    """The first two looks see a person: the robot waits and looks again, then picks from a later look."""
    real_look = episode.Episode.look
    calls = []

    def look(self):
        result = real_look(self)
        calls.append(result)
        if len(calls) <= 2:
            return Look(result.frame, (), result.estimates.__class__({}), 5000, True)
        return result

    monkeypatch.setattr(episode.Episode, "look", look)
    result = episode.run_episode(world, np.random.default_rng(0), poses="oracle")
    assert result.occupied_looks == 0  # counted inside the real look, which saw nobody
    assert len(calls) >= 4
    assert [p.looks for p in result.picks][0] == 3  # two waits, then the pick
    assert all(p.placed for p in result.picks), [p.note for p in result.picks]


@pytest.fixture(scope="module")
def with_person():
    w = build_world(WorldConfig(workpieces=PARTS), np.random.default_rng(1))
    return w, episode.run_episode(w, np.random.default_rng([1, 0]), poses="oracle", occluder=True)


def test_with_the_person_about_the_arm_stops_for_them_and_never_touches_them(with_person):
    _, result = with_person
    assert result.protective_stops >= 1 and result.stopped_s > 0
    assert result.min_human_clearance_mm > 0
    assert all(p.placed for p in result.picks), [p.note for p in result.picks]


def test_an_episode_with_the_person_is_reproducible(with_person):
    _, first = with_person
    w = build_world(WorldConfig(workpieces=PARTS), np.random.default_rng(1))
    again = episode.run_episode(w, np.random.default_rng([1, 0]), poses="oracle", occluder=True)
    assert again.sim_s == first.sim_s and again.protective_stops == first.protective_stops
    for a, b in zip(first.picks, again.picks):
        assert a.note == b.note and a.placed == b.placed
    assert math.isclose(again.min_human_clearance_mm, first.min_human_clearance_mm)
