"""Checks that a cloud is what psorr takes: metres, in the sensor's frame with OpenCV axes.

A cloud in millimetres or in a world frame reads without error, and would otherwise fail deep inside
decomposition or recognition (a depth image terabytes wide); these name the file and the fix instead.
"""

from __future__ import annotations

import numpy as np

from psorr.checks.arrays import rigid_pose
from psorr.errors import InvalidInputError
from psorr.types import PointCloud

SENSOR_RANGE_LIMIT = 25.0  # m: beyond any Kinect-class sensor's reach (about 10 m)
STRAY_LIMIT = 1000.0  # m: no single point of a depth sensor's lies this far
MAX_VIEW_SLOPE = 4.0  # |x| / z or |y| / z: a 152 degree view, wider than depth sensors' (a Kinect's is 57 x 43)


def _spread(cloud: PointCloud, rows: np.ndarray, size: int = 20000) -> np.ndarray:
    """At most about ``size`` of the cloud's finite points (``rows``, their indices), evenly spread. Sampled
    after dropping NaN rows: a stride over every row could land on NaN rows only (an organised cloud's invalid
    pixels recur with the row length). Indices, not a copy of every finite point: that copy (7 MB of a
    640x480 frame) took 3 of these checks' 4 ms."""
    return cloud.points[rows[:: max(1, len(rows) // size)]]


def require_sensor_metres(cloud: PointCloud, what: str) -> None:
    """Refuse a cloud that is evidently not in metres about the sensor: the median distance of its
    finite points from the origin beyond SENSOR_RANGE_LIMIT, as a Kinect cloud in millimetres (about 800)
    is. ``what`` names the cloud in the message (a file, or "the cloud")."""
    _require_metres(cloud, np.flatnonzero(cloud.valid_mask), what)


def _require_metres(cloud: PointCloud, rows: np.ndarray, what: str) -> None:
    sample = _spread(cloud, rows)
    if len(sample) == 0:
        return
    # Single stray values too, which the median lets through: one point 10 km off made a crop grid of
    # 22 GiB, and at 10,000 km Open3D refuses to downsample. fmax and fmin pass over the NaN rows.
    points = cloud.points
    if np.fmax.reduce(points, axis=None) > STRAY_LIMIT or np.fmin.reduce(points, axis=None) < -STRAY_LIMIT:
        finite = points[rows]
        far = np.flatnonzero((np.abs(finite) > STRAY_LIMIT).any(axis=1))
        if len(far):
            worst = far[np.argmax(np.abs(finite[far]).max(axis=1))]
            at = ", ".join(f"{c:.4g}" for c in finite[worst])
            raise InvalidInputError(
                f"{what}: {len(far)} of its {len(finite)} finite points lie more than {STRAY_LIMIT:.0f} m from the "
                f"sensor along an axis (the farthest at ({at}) m); no depth sensor measures that far, so these "
                "are corrupt values: mark them NaN (no measurement) and run again")
    median = float(np.median(np.linalg.norm(sample, axis=1)))
    if median > SENSOR_RANGE_LIMIT:
        raise InvalidInputError(
            f"{what}: its points lie a median {median:.4g} units from the sensor, beyond any depth sensor's "
            f"{SENSOR_RANGE_LIMIT:.0f} m; psorr takes clouds in metres in the sensor's frame (a cloud in "
            "millimetres: scale it by 0.001; one in a world frame: move it into the camera's)")


def require_seen_from_origin(cloud: PointCloud, what: str) -> None:
    """Refuse a cloud that no sensor at the origin looking along +z (OpenCV axes) could have measured:
    one not in metres (:func:`require_sensor_metres`), finite points at z <= 0, or a spread of directions
    wider than MAX_VIEW_SLOPE. Recognition renders the cloud as a depth image from the origin; a
    world-frame cloud (a table at z = 0) would make that image terabytes wide, and points behind the
    sensor would be lost from it. ``what`` names the cloud."""
    rows = np.flatnonzero(cloud.valid_mask)
    _require_metres(cloud, rows, what)
    behind_rows = rows[cloud.points[rows, 2] <= 0]
    behind = len(behind_rows)
    fix = ("psorr takes clouds in the sensor's frame, OpenCV axes: x right, y down, z forward from the sensor; "
           "one in a world frame: move it into the camera's; one with z towards the sensor: negate y and z")
    zeros = int(np.count_nonzero((cloud.points[behind_rows] == 0.0).all(axis=1)))
    if zeros:  # RealSense, Azure Kinect and ROS exports write a pixel without depth so
        raise InvalidInputError(f"{what}: {zeros} of its {len(rows)} finite points are exactly (0, 0, 0), which "
                                "depth sensors and their drivers write for pixels without a measurement; mark "
                                "them NaN (no measurement) and run again")
    if behind:
        raise InvalidInputError(f"{what}: {behind} of its {len(rows)} finite points lie at z <= 0, behind the "
                                f"sensor; {fix}")
    sample = _spread(cloud, rows)
    if len(sample):
        slope = float(np.percentile(np.abs(sample[:, :2]).max(axis=1) / sample[:, 2], 99))
        if slope > MAX_VIEW_SLOPE:
            angle = 2 * np.degrees(np.arctan(slope))
            raise InvalidInputError(f"{what}: its points spread over a {angle:.0f} degree view from the origin, "
                                    f"wider than any depth sensor's; {fix}")


def require_sensor_pose(value, what: str) -> np.ndarray:
    """``value`` as a read-only (4, 4) rigid pose in a sensor's frame, in metres: refused (naming ``what``)
    when it is not one, or puts the model's origin beyond SENSOR_RANGE_LIMIT, as a translation in
    millimetres does. ICP from such a pose finds nothing, and would say nothing."""
    T = np.asarray(value, dtype=float)
    if T.shape != (4, 4) or not np.isfinite(T).all():
        raise InvalidInputError(f"{what} must be a finite (4, 4) pose, got "
                                f"{'shape ' + str(T.shape) if T.shape != (4, 4) else 'NaN or inf in it'}")
    T = rigid_pose(T, what)
    distance = float(np.linalg.norm(T[:3, 3]))
    if distance > SENSOR_RANGE_LIMIT:
        raise InvalidInputError(f"{what} puts the part {distance:.4g} m from the sensor, beyond any depth sensor's "
                                f"{SENSOR_RANGE_LIMIT:g} m: poses are in metres (a translation in millimetres: "
                                "divide it by 1000)")
    return T
