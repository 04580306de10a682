"""How much of an instance in a rendered scene is seen: its model's surface samples, posed, projected into
the image and kept where the depth there is theirs (a z-test two pixels' footprint deep) and, for a
structured-light sensor, where its projector lights them: what lies in the shadow of a nearer object (an
arm over the table) is measured by no such sensor, however plainly the camera sees it."""

from __future__ import annotations

import numpy as np
import trimesh

from psorr.sensing.camera import CameraIntrinsics
from psorr.sensing.kinect_noise import shadow_mask
from psorr.sensing.raycast import render_meshes


def _pixels(points: np.ndarray, intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, columns, inside) of camera-frame points (N, 3); rows and columns are 0 where not inside."""
    z = points[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.rint(intrinsics.fx * points[:, 0] / z + intrinsics.cx)
        v = np.rint(intrinsics.fy * points[:, 1] / z + intrinsics.cy)
    inside = (z > 0) & (u >= 0) & (u < intrinsics.width) & (v >= 0) & (v < intrinsics.height)
    return np.where(inside, v, 0).astype(np.int64), np.where(inside, u, 0).astype(np.int64), inside


def _in_front(depth: np.ndarray, rows, columns, z: np.ndarray, tolerance: np.ndarray) -> np.ndarray:
    """(N,) bool: the image has a return at each pixel no nearer than the point's depth z less the tolerance."""
    at = depth[rows, columns]
    return (at > 0) & (z <= at + tolerance)


def instance_visibility(mesh: trimesh.Trimesh, T_camera_model: np.ndarray, label: int, clean_depth: np.ndarray,
                        clean_ids: np.ndarray, measured_ids: np.ndarray, intrinsics: CameraIntrinsics,
                        samples: int, projector_baseline: float | None = None) -> tuple[float, float]:
    """(visibility, seen share) of one instance: of its surface samples (seeded by the mesh alone) that the
    sensor would see were the instance alone, the share it sees in the clean scene (clean_depth (H, W) in
    metres, clean_ids (H, W) labels); and the share of all samples at a pixel the sensor measured as the
    instance's (measured_ids (H, W)). The mesh is in metres, in its model frame; label is the instance's.
    With ``projector_baseline`` (metres along +x, as KinectNoise.baseline), a sample is seen only where the
    projector lights its pixel, alone and in the scene; None for a sensor that casts no shadow."""
    points = np.asarray(trimesh.sample.sample_surface(mesh, samples, seed=0)[0])
    posed = points @ T_camera_model[:3, :3].T + T_camera_model[:3, 3]
    alone, _ = render_meshes([(mesh.copy().apply_transform(T_camera_model), 1)], np.eye(4), intrinsics)
    rows, columns, inside = _pixels(posed, intrinsics)
    z = posed[:, 2]
    tolerance = 2.0 * z / intrinsics.fx
    seen_alone = inside & _in_front(alone, rows, columns, z, tolerance)
    seen_alone &= _lit(alone, rows, columns, intrinsics, projector_baseline)
    seen = seen_alone & (clean_ids[rows, columns] == label) & _in_front(clean_depth, rows, columns, z, tolerance)
    seen &= _lit(clean_depth, rows, columns, intrinsics, projector_baseline)
    measured = seen & (measured_ids[rows, columns] == label)
    return float(seen.sum() / max(seen_alone.sum(), 1)), float(measured.sum() / len(points))


def _lit(depth: np.ndarray, rows, columns, intrinsics: CameraIntrinsics, baseline: float | None) -> np.ndarray:
    """(N,) bool: the projector lights each sample's pixel in ``depth`` (every one, with no projector)."""
    if baseline is None:
        return np.ones(len(rows), dtype=bool)
    return ~shadow_mask(depth, intrinsics, baseline)[rows, columns]
