"""The MuJoCo cell (sim/world/assembly.py), its Kinect as placed in it and the workpieces' collision hulls. Headless."""

import math

import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull

from psorr.errors import InvalidInputError
from psorr.sensing.camera import CameraIntrinsics
from psorr.sensing.kinect_noise import KinectNoise
from psorr.synthetic.catalog import load_catalog
from sim.devices.render_backend import ensure_headless_gl
from sim.devices.sensor import DepthCamera, T_world_camera_opencv
from sim.world import HOME_KEY, WorldConfig, build_world
from sim.world.assets import COLLISION_DIR
from sim.world.parts import collision_index

SEED = 7
CONFIG = WorldConfig(workpieces=("u_channel", "chassis", "transformer", "pipe_tee", "bushing"))
# Parts whose footprint fills the corners of its bounding box, the fixture's pocket: a 5 deg yaw
# jams them. Round parts, the transformer's round coils and the tee's arms turn 5 deg freely.
BOXY = {"u_channel", "chassis"}


@pytest.fixture(scope="module")
def world():
    return build_world(CONFIG, np.random.default_rng(SEED))


@pytest.fixture(scope="module")
def camera(world):
    with DepthCamera(world.model, world.camera_name, CONFIG.intrinsics) as cam:
        yield cam


@pytest.fixture(scope="module")
def frame(world, camera):
    return camera.render(world.reset(mujoco.MjData(world.model)))


def warnings_of(data):
    return {mujoco.mjtWarning(i).name: int(w.number) for i, w in enumerate(data.warning) if w.number}


def to_world(T, points):
    return points @ T[:3, :3].T + T[:3, 3]


def test_world_steps_one_second_under_random_arm_targets(world):
    data = world.reset(mujoco.MjData(world.model))
    rng = np.random.default_rng(0)
    actuators = [world.model.actuator(a).id for a in world.arm.arm_actuators]
    home = world.model.key(HOME_KEY).ctrl[actuators]
    for step in range(500):
        if step % 125 == 0:  # a new target every 0.25 s
            data.ctrl[actuators] = home + rng.uniform(-0.4, 0.4, len(actuators))
        mujoco.mj_step(world.model, data)
    assert warnings_of(data) == {}
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    moved = np.abs(data.qpos[[world.model.joint(j).qposadr[0] for j in world.arm.arm_joints]] - home)
    assert moved.max() > 0.1  # the arm did follow its targets


def test_parts_rest_on_the_table_and_stay(world):
    data = world.reset(mujoco.MjData(world.model))
    for _ in range(250):
        mujoco.mj_step(world.model, data)
    for name in world.workpieces:
        T = world.T_world_workpieces[name]
        assert abs(T[2, 3] - world.table_top) < 0.002, name  # resting face on the top: not sunk, not flying
        assert T[2, 2] > math.cos(math.radians(1.0)), name  # upright
        assert np.all(np.abs(T[:2, 3]) < np.asarray(CONFIG.table_size) / 2)
        assert np.linalg.norm(world.body_pose(name, data)[:3, 3] - T[:3, 3]) < 5e-4, name  # at rest
        # Asleep, so they cost no contacts until the gripper wakes them (the episodes' grasps show it does).
        assert data.tree_awake[world.model.body_treeid[world.model.body(name).id]] == 0, name
    assert warnings_of(data) == {}


def test_a_part_kept_awake_does_not_sleep(world):
    # Asleep, a part stays where it is when its support goes: one held still against a pad hung in the
    # air once the gripper opened. The part a pick handles is kept awake; let go, it sleeps again.
    from sim.control.cell import ArmCell

    cell = ArmCell(world)
    world.reset(cell.data)
    held, *others = world.workpieces
    trees = {n: world.model.body_treeid[world.model.body(n).id] for n in world.workpieces}
    cell.keep_awake(held)
    cell.step(100)
    assert cell.data.tree_awake[trees[held]] == 1
    assert all(cell.data.tree_awake[trees[n]] == 0 for n in others)
    cell.keep_awake(None)
    cell.step(100)
    assert cell.data.tree_awake[trees[held]] == 0
    assert not cell.data.xfrc_applied.any()
    world.reset(cell.data)


def test_fixtures_hold_their_part_and_reject_a_misplaced_one(world):
    model, data = world.model, mujoco.MjData(world.model)
    for name in world.workpieces:
        fixture = world.T_world_fixtures[name]
        assert abs(fixture[2, 3] - world.table_top) < 1e-9
        geoms = {g for g in range(model.ngeom) if model.geom_bodyid[g] == model.body(f"{name}_fixture").id}
        offsets = [((0.0, 0.0), 0.0), ((0.01, 0.0), 0.0), ((0.0, -0.01), 0.0)]
        offsets += [((0.0, 0.0), 5.0), ((0.0, 0.0), -5.0)] if name in BOXY else []
        for (dx, dy), yaw in offsets:
            world.reset(data)
            c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
            R = fixture[:3, :3] @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
            adr = model.joint(f"{name}_joint").qposadr[0]
            data.qpos[adr:adr + 3] = fixture[:3, 3] + fixture[:3, :3] @ (dx, dy, 0.001)
            mujoco.mju_mat2Quat(data.qpos[adr + 3:adr + 7], R.ravel())
            mujoco.mj_forward(model, data)
            touching = [c for c in data.contact[:data.ncon] if {c.geom1, c.geom2} & geoms and c.dist < 0]
            assert bool(touching) == ((dx, dy, yaw) != (0.0, 0.0, 0.0)), (name, dx, dy, yaw)


def test_table_points_lie_at_the_table_height(world, frame):
    table = frame.cloud.labels == world.model.body("table").id
    assert table.sum() > 50_000
    z = to_world(world.T_world_camera, frame.cloud.points[table])[:, 2]
    assert np.abs(z - world.table_top).max() < 0.002
    np.testing.assert_allclose(frame.T_world_camera, world.T_world_camera)


def test_segmented_points_lie_on_their_meshes(world, frame):
    rng = np.random.default_rng(0)
    T_world_points = to_world(world.T_world_camera, frame.cloud.points)
    for name in world.workpieces:
        mask = frame.segmentation.ravel() == world.model.body(name).id
        assert mask.sum() > 300, name  # every part is in view
        points = T_world_points[mask]
        points = points[rng.choice(len(points), size=min(len(points), 400), replace=False)]
        T = world.T_world_workpieces[name]
        local = (points - T[:3, 3]) @ T[:3, :3]
        mesh = world.catalog[name].load_mesh()
        _, distance, _ = trimesh.proximity.closest_point(mesh, local)
        assert distance.max() < 0.002, (name, distance.max())


def test_same_seed_gives_the_same_world_and_noisy_cloud(world, camera):
    twin = build_world(CONFIG, np.random.default_rng(SEED))
    np.testing.assert_array_equal(twin.model.key(HOME_KEY).qpos, world.model.key(HOME_KEY).qpos)
    for name in world.workpieces:
        np.testing.assert_array_equal(twin.T_world_fixtures[name], world.T_world_fixtures[name])
    noise = KinectNoise()
    with DepthCamera(twin.model, twin.camera_name) as twin_camera:
        a = camera.render(world.reset(mujoco.MjData(world.model)), np.random.default_rng(3), noise)
        b = twin_camera.render(twin.data, np.random.default_rng(3), noise)
    np.testing.assert_array_equal(a.cloud.points, b.cloud.points)
    np.testing.assert_array_equal(a.cloud.labels, b.cloud.labels)
    assert 0.5 < np.isfinite(a.cloud.points[:, 2]).mean() < 0.99  # the noise dropped some pixels, not most
    other = build_world(CONFIG, np.random.default_rng(SEED + 1))
    assert not np.allclose(other.T_world_fixtures["chassis"], world.T_world_fixtures["chassis"])


def _inside_any(files, points):
    inside = np.zeros(len(points), dtype=bool)
    for file in files:
        hull = ConvexHull(trimesh.load(COLLISION_DIR / file, force="mesh").vertices)
        inside |= np.all(points @ hull.equations[:, :3].T + hull.equations[:, 3] <= 1e-9, axis=1)
    return inside


def test_collision_hulls_keep_the_cavities_open():
    index = collision_index()
    assert set(index) == set(load_catalog())
    assert sum(p.stat().st_size for p in COLLISION_DIR.glob("*.stl")) < 3e6
    assert max(len(entry["files"]) for entry in index.values()) <= 16
    channel, tray = index["u_channel"]["files"], index["chassis"]["files"]
    # Middle of the U-channel (web top z = 4 mm, walls to 30 mm) and of the chassis tray: free.
    assert not _inside_any(channel, np.array([[0, 0, 0.017], [0.05, 0, 0.01], [-0.05, 0, 0.025]])).any()
    assert not _inside_any(tray, np.array([[0, 0, 0.02], [0.05, 0.02, 0.01]])).any()
    # ...while the material around it is covered: the web, both walls, the tray bottom and a side.
    assert _inside_any(channel, np.array([[0, 0, 0.002], [0, 0.023, 0.02], [0, -0.023, 0.02]])).all()
    assert _inside_any(tray, np.array([[0.0, 0.0, 0.0007], [0.0, 0.0322, 0.02]])).all()


def test_camera_projects_with_f_525(world):
    assert world.model.cam_fovy[world.model.camera(world.camera_name).id] == pytest.approx(49.134, abs=1e-3)
    intrinsics = CONFIG.intrinsics
    pixels = np.array([[60.0, 50.0], [580.0, 50.0], [60.0, 430.0], [580.0, 430.0], [319.5, 239.5]])
    rays = np.column_stack([(pixels - (intrinsics.cx, intrinsics.cy)) / intrinsics.fx, np.ones(len(pixels))])
    centres = to_world(world.T_world_camera, 0.45 * rays)  # 0.45 m in front of the camera, nearer than the arm
    spec = world.spec.copy()
    for k, centre in enumerate(centres):
        probe = spec.worldbody.add_body(name=f"probe_{k}", pos=centre)
        probe.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.003], contype=0, conaffinity=0)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    np.testing.assert_allclose(T_world_camera_opencv(model, data, world.camera_name), world.T_world_camera)
    with DepthCamera(model, world.camera_name, intrinsics) as camera:
        segmentation = camera.render(data).segmentation
    T_camera_world = np.linalg.inv(world.T_world_camera)
    for k, centre in enumerate(centres):
        rows, cols = np.nonzero(segmentation == model.body(f"probe_{k}").id)
        assert len(rows) > 10
        expected = intrinsics.project(to_world(T_camera_world, centre[None]))[0]
        np.testing.assert_allclose([cols.mean(), rows.mean()], expected, atol=0.3)
        np.testing.assert_allclose(expected, pixels[k], atol=1e-9)


def test_bad_configs_name_the_valid_choices():
    with pytest.raises(InvalidInputError, match=r"\[0.6, 1.0\]"):
        WorldConfig(camera_height=1.5)
    with pytest.raises(InvalidInputError, match="choose from"):
        build_world(WorldConfig(workpieces=("gear",)), np.random.default_rng(0))
    with pytest.raises(InvalidInputError, match="rng"):
        build_world(CONFIG, None)
    with pytest.raises(InvalidInputError, match="centred"):
        WorldConfig(intrinsics=CameraIntrinsics(cx=300.0))
    assert ensure_headless_gl() in ("egl", "osmesa", "glfw", "glx")
