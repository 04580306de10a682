"""The supporting plane of a table-top scene: the largest plane, found by Open3D's RANSAC."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d

from psorr.geometry.open3d_threads import single_threaded
from psorr.sensing.kinect_noise import KINECT_V1
from psorr.sensing.noise_context import depth_noise

_DISTANCE = 0.008  # m: a plane's inlier band for a Kinect v1, three of its depth sigmas at 1.2 m
_BAND_DEPTH = 1.2  # m: where the band is measured in the sensor's sigmas
_MIN_SHARE = 0.2   # of the points: a smaller largest plane is no table
_REFITS = 5        # least-squares refits of RANSAC's plane: two or three settle its inliers


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
        distance = band()
        plane, inliers = cloud.segment_plane(distance_threshold=distance, ransac_n=3, num_iterations=200)
    if len(inliers) <= _MIN_SHARE * len(cloud.points):
        return None
    plane, inliers = _refined(np.asarray(cloud.points), np.asarray(plane, float), np.asarray(inliers, dtype=np.int64),
                              distance)
    return SupportPlane(plane if plane[3] > 0 else -plane, inliers)


def band() -> float:
    """The plane's inlier band (m): _DISTANCE for a Kinect v1, as many of the sensor's depth sigmas at 1.2 m
    for another (``RecognizeParams.sensor``)."""
    return _DISTANCE * float(depth_noise().depth_sigma(_BAND_DEPTH) / KINECT_V1.depth_sigma(_BAND_DEPTH))


def _refined(points: np.ndarray, plane: np.ndarray, inliers: np.ndarray,
             distance: float) -> tuple[np.ndarray, np.ndarray]:
    """The least-squares plane of the points within ``distance`` of ``plane``, refitted until its inliers stay
    the same (at most _REFITS times), and those inliers. RANSAC's plane is the best of its draws, which
    depend on the points' order; the least-squares plane of a hundred thousand inliers does not."""
    plane = plane / np.linalg.norm(plane[:3])
    for _ in range(_REFITS):
        fitted = points[inliers]
        centre = fitted.mean(axis=0)
        spread = fitted - centre
        normal = np.linalg.eigh(spread.T @ spread)[1][:, 0]
        normal = normal if normal @ plane[:3] > 0 else -normal
        plane = np.append(normal, -normal @ centre)
        again = np.flatnonzero(np.abs(points @ normal + plane[3]) <= distance)
        if np.array_equal(again, inliers):
            break
        inliers = again
    return plane, inliers
