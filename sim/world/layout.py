"""Where the parts and their fixtures go on the table: seeded, apart, within reach and in view.

Pure geometry on the table top (world frame, metres, yaw in radians) plus ray casts against a
bare model of the table, arm and camera; :func:`sim.world.build_world` assembles the result.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from sim.devices.sensor import T_world_camera_opencv
from sim.errors import WorldBuildError

if TYPE_CHECKING:
    from sim.world.config import WorldConfig


def yaw_matrix(theta: float) -> np.ndarray:
    """(3, 3) rotation by ``theta`` radians about the world's z axis."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _footprint(bounds, x: float, y: float, yaw: float, pad: float) -> np.ndarray:
    """(4, 2) world corners of a model-frame footprint ``bounds`` ((2,) lo, (2,) hi) grown by ``pad``."""
    (x0, y0), (x1, y1) = bounds[0] - pad, bounds[1] + pad
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]) @ yaw_matrix(yaw)[:2, :2].T + (x, y)


def _overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two convex quads (4, 2) overlap (separating axis test)."""
    for edge in np.concatenate([np.roll(a, -1, axis=0) - a, np.roll(b, -1, axis=0) - b]):
        pa, pb = a @ (-edge[1], edge[0]), b @ (-edge[1], edge[0])
        if pa.max() < pb.min() or pb.max() < pa.min():
            return False
    return True


def place_parts(cfg: WorldConfig, items, base_xy, bare: mujoco.MjModel, home: str, camera: str,
                rng: np.random.Generator) -> dict:
    """Seeded non-overlapping (x, y, yaw) for each (key, bounds, pad): on the table, in reach, and seen by
    the camera past the arm at home (``bare`` holds only table, arm and camera)."""
    data = mujoco.MjData(bare)
    mujoco.mj_resetDataKeyframe(bare, data, bare.key(home).id)
    mujoco.mj_forward(bare, data)
    T_world_camera = T_world_camera_opencv(bare, data, camera)
    T_camera_world, eye = np.linalg.inv(T_world_camera), T_world_camera[:3, 3]
    half, top, size = np.asarray(cfg.table_size) / 2, cfg.table_height, np.array(cfg.intrinsics.shape[::-1])
    groups, table = np.array([0, 0, 1, 0, 0, 0], np.uint8), bare.body("table").id

    def fits(quad) -> bool:
        dist = np.linalg.norm(quad - base_xy, axis=1)
        if np.any(np.abs(quad) > half - 0.02) or dist.min() < cfg.reach[0] or dist.max() > cfg.reach[1]:
            return False
        points = np.column_stack([np.vstack([quad, quad.mean(0)]), np.full(5, top + 0.005)])
        uv = cfg.intrinsics.project(points @ T_camera_world[:3, :3].T + T_camera_world[:3, 3])
        if not (np.all(np.isfinite(uv)) and np.all(uv >= 20) and np.all(uv <= size - 21)):
            return False
        for point in points:  # nothing of the arm (visual group 2) between the camera and the point
            ray, geom = point - eye, np.array([-1], np.int32)
            hit = mujoco.mj_ray(bare, data, eye, ray / np.linalg.norm(ray), groups, 1, table, geom)
            if 0 <= hit < np.linalg.norm(ray):
                return False
        return True

    placed, quads = {}, []
    for key, bounds, pad in sorted(items, key=lambda it: -np.prod(it[1][1] - it[1][0] + 2 * it[2])):
        for _ in range(1000):
            pose = (rng.uniform(-half[0], half[0]), rng.uniform(-half[1], half[1]), rng.uniform(0.0, 2 * np.pi))
            quad = _footprint(bounds, *pose, pad)
            if not any(_overlap(quad, other) for other in quads) and fits(quad):
                placed[key] = pose
                quads.append(quad)
                break
        else:
            raise WorldBuildError(
                f"found no free spot for {key} on the table: place fewer workpieces (got {len(cfg.workpieces)}), "
                f"enlarge table_size or reach, or set fixtures=False"
            )
    return placed
