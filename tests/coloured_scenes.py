"""Coloured scenes built in the tests: identical boxes in colours of their own, on a table."""

from __future__ import annotations

import numpy as np
import trimesh

from psorr import PointCloud
from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, look_at
from psorr.sensing.kinect_noise import kinect_noise_with_source
from psorr.sensing.raycast import render_meshes

RED, BLUE, GREY = (0.8, 0.1, 0.1), (0.1, 0.25, 0.8), (0.55, 0.5, 0.45)


def two_boxes(colours, gap: float, seed: int = 0) -> tuple[PointCloud, np.ndarray]:
    """Two identical 10 x 6 x 5 cm boxes side by side ``gap`` metres apart on a table, seen by a Kinect
    from 0.8 m, coloured ``colours`` with a little colour noise; and the truth: 1 table, 2 and 3 the boxes."""
    boxes = []
    for k in range(2):
        box = trimesh.creation.box((0.10, 0.06, 0.05))
        box.apply_translation((0.0, (k - 0.5) * (0.06 + gap), 0.025))
        boxes.append(box)
    return _seen(boxes, colours, seed)


def stacked_boxes(colours, seed: int = 0) -> tuple[PointCloud, np.ndarray]:
    """A 7 x 5 x 4 cm box standing on a 14 x 10 x 5 cm one, turned 30 degrees on it, seen and coloured as
    in two_boxes; truth 2 is the lower box, 3 the upper."""
    lower = trimesh.creation.box((0.14, 0.10, 0.05))
    lower.apply_translation((0.0, 0.0, 0.025))
    upper = trimesh.creation.box((0.07, 0.05, 0.04))
    upper.apply_transform(trimesh.transformations.rotation_matrix(np.radians(30), (0, 0, 1)))
    upper.apply_translation((0.01, -0.01, 0.07))
    return _seen([lower, upper], colours, seed)


def _seen(boxes, colours, seed: int) -> tuple[PointCloud, np.ndarray]:
    table = trimesh.creation.box((0.8, 0.8, 0.02))
    table.apply_translation((0, 0, -0.01))
    intrinsics = CameraIntrinsics()
    rng = np.random.default_rng(seed)
    depth, ids = render_meshes([(table, 1), (boxes[0], 2), (boxes[1], 3)], look_at((0.45, -0.2, 0.65), (0, 0, 0)),
                               intrinsics)
    noisy, source = kinect_noise_with_source(depth, intrinsics, rng)
    truth = ids.ravel()[source.ravel()]
    palette = np.array([GREY, GREY, *colours])  # ids -1 (nothing) and 1 (table) grey
    rgb = np.clip(palette[np.clip(truth, 0, 3)] + rng.normal(0, 0.02, (len(truth), 3)), 0, 1)
    cloud = depth_to_cloud(noisy, intrinsics, colors=rgb.reshape(intrinsics.height, intrinsics.width, 3))
    return cloud, np.where(cloud.valid_mask, truth, -1)
