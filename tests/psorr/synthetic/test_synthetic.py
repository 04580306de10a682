"""Synthetic ray-cast scenes and their ground truth."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from psorr.errors import InvalidInputError
from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud
from psorr.synthetic.primitive_scenes import (
    SMALL_SURFACE_LABEL,
    box_on_table,
    box_with_boss,
    cylinder_on_table,
    empty_table,
    look_at,
    render_meshes,
)

SCENES = {f.__name__: f for f in (empty_table, box_on_table, cylinder_on_table, box_with_boss)}


@pytest.fixture(scope="module")
def scenes():
    return {name: make(np.random.default_rng(11)) for name, make in SCENES.items()}


def clean_points(scene, surface_id: int) -> np.ndarray:
    cloud = depth_to_cloud(scene.depth_clean, scene.intrinsics, labels=scene.surface_ids)
    return cloud.points[cloud.labels == surface_id]


def plane_residuals(points, params) -> np.ndarray:
    return points @ np.array(params[:3]) + params[3]


def radial_residuals(points, params) -> np.ndarray:
    p, a, r = np.array(params[:3]), np.array(params[3:6]), params[6]
    rel = points - p
    return np.linalg.norm(rel - np.outer(rel @ a, a), axis=1) - r


def test_look_at_gives_opencv_axes():
    T = look_at((0.0, -0.3, 0.8), (0.0, 0.0, 0.0))
    R = T[:3, :3]
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)
    forward = np.array([0.0, 0.3, -0.8]) / np.linalg.norm([0.3, 0.8])
    np.testing.assert_allclose(R[:, 2], forward, atol=1e-12)
    np.testing.assert_allclose(R[:, 0], [1.0, 0.0, 0.0], atol=1e-12)  # x to the right
    assert R[2, 1] < 0  # image y points down in the world
    np.testing.assert_allclose(T[:3, 3], [0.0, -0.3, 0.8])
    with pytest.raises(InvalidInputError):
        look_at((0.0, 0.0, 1.0), (0.0, 0.0, 0.0))


@pytest.mark.parametrize("name", list(SCENES))
def test_scene_renders_with_consistent_truth(scenes, name):
    scene = scenes[name]
    h, w = scene.intrinsics.shape
    assert (h, w) == (480, 640) and scene.cloud.is_organised and len(scene.cloud) == h * w
    assert scene.depth.shape == scene.depth_clean.shape == scene.surface_ids.shape == (h, w)
    assert [s.id for s in scene.surfaces] == list(range(len(scene.surfaces)))
    assert scene.surface("table_top").kind == "plane"
    labels = scene.cloud.labels
    assert set(np.unique(labels)) <= {-1, SMALL_SURFACE_LABEL, *range(len(scene.surfaces))}
    np.testing.assert_array_equal(labels == -1, scene.depth.ravel() == 0)
    assert scene.cloud.valid_mask.mean() > 0.6
    for truth in scene.surfaces:
        assert (scene.surface_ids == truth.id).sum() >= 200
        if truth.kind == "plane":
            assert truth.params[3] > 0  # n points towards the camera at the origin
            assert np.linalg.norm(truth.params[:3]) == pytest.approx(1.0)


def test_table_top_is_the_world_plane_seen_from_the_camera(scenes):
    for scene in scenes.values():
        table = scene.surface("table_top")
        points = clean_points(scene, table.id)
        assert len(points) > 50_000
        assert np.abs(plane_residuals(points, table.params)).max() < 5e-4
        T = scene.T_world_camera
        np.testing.assert_allclose(T[:3, :3] @ table.params[:3], [0.0, 0.0, 1.0], atol=1e-12)
        world = points @ T[:3, :3].T + T[:3, 3]
        assert np.abs(world[:, 2]).max() < 5e-4
        assert 0.6 <= T[2, 3] <= 1.0  # camera height above the table


def test_box_faces_lie_on_their_planes(scenes):
    scene = scenes["box_with_boss"]
    planes = [s for s in scene.surfaces if s.kind == "plane"]
    assert {"box_top", "boss_top"} <= {s.name for s in planes}
    for truth in planes:
        assert np.abs(plane_residuals(clean_points(scene, truth.id), truth.params)).max() < 5e-4


@pytest.mark.parametrize("scene_name, name", [("cylinder_on_table", "cylinder_side"),
                                              ("box_with_boss", "boss_side")])
def test_cylinder_points_lie_at_the_truth_radius(scenes, scene_name, name):
    scene = scenes[scene_name]
    truth = scene.surface(name)
    assert truth.kind == "cylinder"
    points = clean_points(scene, truth.id)
    assert np.abs(radial_residuals(points, truth.params)).max() < 5e-4
    T = scene.T_world_camera
    axis_world = T[:3, :3] @ truth.params[3:6]
    centre_world = T[:3, :3] @ truth.params[:3] + T[:3, 3]
    if scene_name == "cylinder_on_table":  # lying: horizontal axis at one radius height
        assert abs(axis_world[2]) < 1e-9
        assert centre_world[2] == pytest.approx(truth.params[6])
    else:  # the boss stands upright
        assert abs(abs(axis_world[2]) - 1.0) < 1e-9


def test_noisy_cloud_points_stay_near_their_surfaces(scenes):
    scene = scenes["cylinder_on_table"]
    labels, points = scene.cloud.labels, scene.cloud.points
    table, side = scene.surface("table_top"), scene.surface("cylinder_side")
    assert np.median(np.abs(plane_residuals(points[labels == table.id], table.params))) < 0.01
    assert np.median(np.abs(radial_residuals(points[labels == side.id], side.params))) < 0.01


def test_adjacent_pairs_touch_in_the_image(scenes):
    expected = {
        "box_on_table": [("table_top", "box_top")],
        "cylinder_on_table": [("table_top", "cylinder_side")],
        "box_with_boss": [("box_top", "boss_side"), ("boss_side", "boss_top")],
    }
    for name, scene in scenes.items():
        ids = scene.surface_ids
        names = {s.id: s.name for s in scene.surfaces}
        for i, j in scene.adjacent:
            assert i < j
            a, b = ids == i, ids == j
            across = (a[:, :-1] & b[:, 1:]) | (b[:, :-1] & a[:, 1:])
            down = (a[:-1] & b[1:]) | (b[:-1] & a[1:])
            assert across.sum() + down.sum() >= 3, (name, names[i], names[j])
        pairs = {frozenset((names[i], names[j])) for i, j in scene.adjacent}
        for a, b in expected.get(name, []):
            if a == "table_top" and b == "box_top":  # the box top meets the table via a side
                assert any("table_top" in p and any(n.startswith("box_") for n in p) for p in pairs)
                assert any("box_top" in p and len(p & {"box_+x", "box_-x", "box_+y", "box_-y"})
                           for p in pairs)
            else:
                assert frozenset((a, b)) in pairs
        assert frozenset(("table_top", "box_top")) not in pairs  # they do not touch


def test_same_seed_gives_identical_scenes_and_noise_none_is_clean():
    a = box_on_table(np.random.default_rng(5))
    b = box_on_table(np.random.default_rng(5))
    np.testing.assert_array_equal(a.cloud.points, b.cloud.points)
    np.testing.assert_array_equal(a.cloud.labels, b.cloud.labels)
    assert a.surfaces == b.surfaces and a.adjacent == b.adjacent
    clean = box_on_table(np.random.default_rng(5), noise=None)
    assert clean.surfaces == a.surfaces  # the layout draws come before the noise draws
    np.testing.assert_array_equal(clean.depth, clean.depth_clean)
    np.testing.assert_array_equal(clean.cloud.labels.reshape(480, 640), clean.surface_ids)
    other = box_on_table(np.random.default_rng(6))
    assert not np.array_equal(other.depth, a.depth)
    with pytest.raises(ValueError):
        a.depth[0, 0] = 1.0  # read-only


def test_render_meshes_of_a_plain_mesh():
    intrinsics = CameraIntrinsics(width=64, height=48, fx=52.5, fy=52.5, cx=31.5, cy=23.5)
    square = trimesh.creation.box(extents=(4.0, 4.0, 0.01), transform=np.eye(4))
    T = look_at((0.0, 0.0, 1.005), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0))
    depth, ids = render_meshes([(square, 7)], T, intrinsics)
    np.testing.assert_allclose(depth, 1.0, atol=1e-12)
    assert (ids == 7).all()
    depth, ids = render_meshes([], T, intrinsics)
    assert (depth == 0).all() and (ids == -1).all()
