"""Poses no resting part can take: inside the table (psorr/acceptance/accept.py's sinks_into_table)."""

import copy

import numpy as np
import pytest
import trimesh

from psorr.acceptance.accept import sinks_into_table
from psorr.acceptance.params import AcceptParams
from psorr.synthetic.mesh_scenes import SceneParams, mesh_scene
from psorr.verification.scene_view import SceneView

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")

CHECK = AcceptParams().check


@pytest.fixture(scope="module")
def lone_box():
    """A 40 x 30 x 20 mm box alone on the table 0.8 m from the camera: (view, its samples, T_camera_model, the
    table's normal in the camera frame)."""
    mesh = trimesh.creation.box([0.04, 0.03, 0.02])
    params = SceneParams(camera_distance=(0.8, 0.8), camera_tilt_deg=(20.0, 20.0))
    scene = mesh_scene(np.random.default_rng(0), {"box": mesh}, "single", params=params)
    view = SceneView(scene.cloud)
    points = np.asarray(trimesh.sample.sample_surface_even(mesh, 2000, seed=0)[0])
    return view, points, scene.instances[0].T_camera_model, view.support_plane[:3]


def _moved(T: np.ndarray, offset: np.ndarray) -> np.ndarray:
    T = T.copy()
    T[:3, 3] += offset
    return T


def test_a_box_resting_on_the_table_does_not_sink_into_it(lone_box):
    view, points, T, _ = lone_box
    assert not sinks_into_table(view, points, T, CHECK)


def test_the_box_pushed_half_into_the_table_does(lone_box):
    view, points, T, up = lone_box
    assert sinks_into_table(view, points, _moved(T, -0.01 * up), CHECK)
    # on bare table beside it too, where the sensor sees only the table over it
    beside = np.cross(up, [1.0, 0.0, 0.0])
    assert sinks_into_table(view, points, _moved(T, -0.01 * up + 0.1 * beside / np.linalg.norm(beside)), CHECK)


def test_below_the_table_by_less_than_the_depth_tolerance_is_a_resting_pose_off_by_noise(lone_box):
    view, points, T, up = lone_box
    assert not sinks_into_table(view, points, _moved(T, -0.002 * up), CHECK)  # tolerance about 5 mm at 0.8 m


def test_without_a_supporting_plane_nothing_sinks(lone_box):
    view, points, T, up = lone_box
    planeless = copy.copy(view)
    planeless.support_plane = None
    assert not sinks_into_table(planeless, points, _moved(T, -0.01 * up), CHECK)
