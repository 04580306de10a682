"""The supporting plane of a table-top scene: the largest plane, found by Open3D's RANSAC."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d

from psorr.geometry.open3d_threads import single_threaded

_DISTANCE = 0.008  # m: a plane's inlier band, three Kinect depth sigmas at 1.2 m
_MIN_SHARE = 0.2   # of the points: a smaller largest plane is no table


@dataclass(frozen=True, eq=False)
class SupportPlane:
    """plane: (4,) a, b, c, d with a unit normal and the sensor (origin) on its positive side;
    inliers: (K,) indices of the points that lie on it."""

    plane: np.ndarray
    inliers: np.ndarray


def support_plane(cloud: o3d.geometry.PointCloud) -> SupportPlane | None:
    """The largest plane of ``cloud`` (a downsampled scene in the sensor frame), or None when it holds
    under a fifth of the points. Seeded and single-threaded, so one cloud gives one plane."""
    if len(cloud.points) < 3:
        return None
    o3d.utility.random.seed(0)
    with single_threaded():
        plane, inliers = cloud.segment_plane(distance_threshold=_DISTANCE, ransac_n=3, num_iterations=200)
    if len(inliers) <= _MIN_SHARE * len(cloud.points):
        return None
    plane = np.asarray(plane, float) / np.linalg.norm(plane[:3])
    return SupportPlane(plane if plane[3] > 0 else -plane, np.asarray(inliers, dtype=np.int64))
