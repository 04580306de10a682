"""An instance's visibility counts what a structured-light sensor can measure: the camera must see a
sample and the projector must light it."""

import numpy as np
import trimesh

from psorr.sensing.camera import CameraIntrinsics
from psorr.sensing.kinect_noise import KINECT_V1
from psorr.sensing.raycast import render_meshes
from psorr.synthetic.scene_visibility import instance_visibility

INTRINSICS = CameraIntrinsics()


def _box(extents, centre) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(centre)
    return mesh


def _visibility(baseline):
    """A 2 cm cube 1 m in front of the camera, and a plate half a metre away whose left edge covers only
    the cube's rightmost millimetres: the camera sees most of the cube past it, but the projector, 7.5 cm
    to the camera's right, lights the cube past the plate's edge from further right, and cannot."""
    part = _box((0.02, 0.02, 0.02), (0.0, 0.0, 0.0))
    T_camera_model = np.eye(4)
    T_camera_model[2, 3] = 1.0
    plate = _box((0.1, 0.1, 0.005), (0.0032 + 0.05, 0.0, 0.5))
    world = [(part.copy().apply_transform(T_camera_model), 1), (plate, 2)]
    depth, ids = render_meshes(world, np.eye(4), INTRINSICS)
    return instance_visibility(part, T_camera_model, 1, depth, ids, ids, INTRINSICS, 2000, baseline)[0]


def test_a_part_in_the_projector_shadow_of_a_nearer_object_is_not_visible():
    assert _visibility(None) > 0.6  # the camera alone sees most of it past the plate
    assert _visibility(KINECT_V1.baseline) < 0.1  # the plate's shadow falls on it


def test_a_part_alone_is_fully_visible_with_or_without_the_projector():
    part = _box((0.02, 0.02, 0.02), (0.0, 0.0, 0.0))
    T = np.eye(4)
    T[2, 3] = 1.0
    depth, ids = render_meshes([(part.copy().apply_transform(T), 1)], np.eye(4), INTRINSICS)
    for baseline in (None, KINECT_V1.baseline):
        assert instance_visibility(part, T, 1, depth, ids, ids, INTRINSICS, 2000, baseline)[0] == 1.0
