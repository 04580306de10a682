"""The simulated human occluder (sim/people/occluder.py) in the cell (sim/world/assembly.py). Headless."""

import dataclasses

import mujoco
import numpy as np
import pytest

from psorr.errors import InvalidInputError
from sim.devices.sensor import DepthCamera
from sim.people.occluder import FOREARM, UPPER_ARM, ReachSchedule, occluder_pose, occlusion_at
from sim.world import HOME_KEY, WorldConfig, build_world

SEED = 7
CONFIG = WorldConfig(workpieces=("u_channel", "chassis", "transformer", "pipe_tee", "bushing"))


@pytest.fixture(scope="module")
def world():
    return build_world(CONFIG, np.random.default_rng(SEED))


def warnings_of(data):
    return {mujoco.mjtWarning(i).name: int(w.number) for i, w in enumerate(data.warning) if w.number}


def occluder_bodies(world):
    return [world.model.body(name).id for name in world.occluder_geoms]


def target_part(world):
    xy = np.asarray(world.occluder.target_xy)
    return min(world.workpieces, key=lambda n: np.linalg.norm(world.T_world_workpieces[n][:2, 3] - xy))


def test_world_exposes_the_occluder_as_non_colliding_mocap_capsules(world):
    model = world.model
    assert world.occluder_geoms == ("human/torso", "human/upper_arm", "human/forearm", "human/hand")
    for name in world.occluder_geoms:
        geom = model.geom(name)
        assert geom.type[0] == mujoco.mjtGeom.mjGEOM_CAPSULE
        assert geom.contype[0] == 0 and geom.conaffinity[0] == 0
        assert model.body_mocapid[geom.bodyid[0]] >= 0
    assert len(model.key(HOME_KEY).mpos) == 3 * model.nmocap


def test_world_steps_one_second_through_the_whole_reach_without_moving_parts(world):
    # The sampled schedule, squeezed into 1 s: rest, reach, pause, withdraw, rest.
    schedule = dataclasses.replace(world.occluder, start_s=0.1, reach_s=0.3, pause_s=0.2, withdraw_s=0.3)
    model, data = world.model, world.reset(mujoco.MjData(world.model))
    geoms = {model.geom(name).id for name in world.occluder_geoms}
    peak = 0.0
    for _ in range(round(1.0 / model.opt.timestep)):
        world.apply_occluder(data, data.time, schedule)
        mujoco.mj_step(model, data)
        assert not any({c.geom1, c.geom2} & geoms for c in data.contact[:data.ncon])
        peak = max(peak, occlusion_at(schedule, data.time))
    assert peak == 1.0 and occlusion_at(schedule, data.time) == 0.0  # went all the way and came back
    assert warnings_of(data) == {}
    for name in world.workpieces:
        moved = np.linalg.norm(world.body_pose(name, data)[:3, 3] - world.T_world_workpieces[name][:3, 3])
        assert moved < 5e-4, (name, moved)


def test_at_the_peak_the_hand_hides_the_target_part_and_is_out_of_view_at_rest(world):
    schedule = world.occluder
    bodies, part = occluder_bodies(world), world.model.body(target_part(world)).id
    data = mujoco.MjData(world.model)
    segs = {}
    with DepthCamera(world.model, world.camera_name, CONFIG.intrinsics) as camera:
        for when, t in (("before", schedule.start_s - 0.01), ("peak", sum(schedule.peak_s) / 2),
                        ("after", schedule.end_s + 0.01)):
            world.apply_occluder(world.reset(data), t)
            mujoco.mj_forward(world.model, data)
            segs[when] = camera.render(data).segmentation
    visible = segs["before"] == part
    assert visible.sum() > 300
    covered = np.isin(segs["peak"][visible], bodies).mean()
    assert covered > 0.3, covered
    hand = world.model.body("human/hand").id
    assert np.any(segs["peak"] == hand)
    assert not np.isin(segs["before"], bodies).any() and not np.isin(segs["after"], bodies).any()


def test_hand_passes_between_camera_and_parts_at_the_set_height(world):
    s = world.occluder
    assert 0.15 <= s.hand_height <= 0.25
    peak = occluder_pose(s, sum(s.peak_s) / 2)
    hand = peak["human/hand"][:3, 3]
    np.testing.assert_allclose(hand, [*s.hand_xy, s.table_top + s.hand_height], atol=0.03)
    # segment lengths are kept throughout
    for t in np.linspace(s.start_s - 0.5, s.end_s + 0.5, 23):
        pose = occluder_pose(s, t)
        z = {n: T[:3, 2] for n, T in pose.items()}
        p = {n: T[:3, 3] for n, T in pose.items()}
        elbow = p["human/upper_arm"] + z["human/upper_arm"] * UPPER_ARM / 2
        np.testing.assert_allclose(p["human/forearm"] - z["human/forearm"] * FOREARM / 2, elbow, atol=1e-9)
    # at rest the arm is beyond the table's +x edge
    rest = occluder_pose(s, s.start_s - 0.1)
    assert all(T[0, 3] > s.edge_x for T in rest.values())


def test_occlusion_is_smooth_and_peaks_during_the_pause():
    s = ReachSchedule(start_s=0.5, reach_s=1.0, pause_s=0.4, withdraw_s=0.8, target_xy=(0.1, 0.0),
                      hand_xy=(0.15, 0.0), hand_height=0.2, shoulder_y=0.1, edge_x=0.45, table_top=0.75)
    t = np.linspace(0.0, 3.0, 3001)
    k = np.array([occlusion_at(s, x) for x in t])
    assert k.min() == 0.0 and k.max() == 1.0
    assert np.all(k[(t > s.peak_s[0]) & (t < s.peak_s[1])] == 1.0)
    assert np.all(k[(t < s.start_s) | (t > s.end_s)] == 0.0)
    assert np.abs(np.diff(k)).max() < 1.9 / 0.8 * 1e-3  # no jumps: minimum jerk peaks at 1.875 / duration per s
    # the hand moves continuously
    hands = np.array([occluder_pose(s, x)["human/hand"][:3, 3] for x in t[::10]])
    assert np.linalg.norm(np.diff(hands, axis=0), axis=1).max() < 0.02


def test_same_seed_same_schedule_and_the_layout_does_not_depend_on_the_occluder(world):
    twin = build_world(CONFIG, np.random.default_rng(SEED))
    assert twin.occluder == world.occluder
    other = build_world(CONFIG, np.random.default_rng(SEED + 1))
    assert other.occluder != world.occluder
    bare = build_world(dataclasses.replace(CONFIG, occluder=False), np.random.default_rng(SEED))
    assert bare.occluder is None and bare.occluder_geoms == () and bare.model.nmocap == 0
    np.testing.assert_array_equal(bare.model.key(HOME_KEY).qpos, world.model.key(HOME_KEY).qpos)
    with pytest.raises(InvalidInputError, match="occluder"):
        bare.apply_occluder(mujoco.MjData(bare.model), 1.0)
    a = ReachSchedule.sample(np.random.default_rng(3), (0.9, 1.0), 0.75)
    assert a == ReachSchedule.sample(np.random.default_rng(3), (0.9, 1.0), 0.75)


def test_bad_schedules_are_refused():
    base = dict(start_s=0.0, reach_s=1.0, pause_s=0.5, withdraw_s=1.0, target_xy=(0.0, 0.0), hand_xy=(0.0, 0.0),
                hand_height=0.2, shoulder_y=0.0, edge_x=0.45, table_top=0.75)
    for change in ({"reach_s": 0.0}, {"pause_s": -1.0}, {"hand_height": 0.0}, {"target_xy": (0.0, 0.0, 1.0)}):
        with pytest.raises(InvalidInputError):
            ReachSchedule(**{**base, **change})
    with pytest.raises(InvalidInputError, match="rng"):
        ReachSchedule.sample(None, (0.9, 1.0), 0.75)


def test_occluder_geoms_serve_as_ik_collision_avoidance_geoms(world):
    from sim.control.ik import ArmIK

    ik = ArmIK(world.model, world.arm)
    limit = ik._collision_limit([(world.arm.collision_geoms, world.occluder_geoms)])
    human = {world.model.geom(name).id for name in world.occluder_geoms}
    assert {g for pair in limit.geom_id_pairs for g in pair} >= human  # mink did not drop them
    assert not world.model.geom_contype[list(human)].any() and not world.model.geom_conaffinity[list(human)].any()
    q = world.model.key(HOME_KEY).qpos.copy()
    result = ik.solve(q, _tool_pose(world, q), collision_geoms=[(world.arm.collision_geoms, world.occluder_geoms)])
    assert result.converged


def _tool_pose(world, q):
    from sim.control.ik import T_world_site

    data = mujoco.MjData(world.model)
    data.qpos[:] = q
    mujoco.mj_forward(world.model, data)
    T = T_world_site(world.model, data, world.arm.tool_site).copy()
    T[2, 3] -= 0.05
    return T
