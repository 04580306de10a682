"""PointCloud's own checks, and the sensor-frame checks recognition makes of a cloud."""

import numpy as np
import pytest

from psorr.checks.clouds import require_seen_from_origin, require_sensor_metres
from psorr.errors import InvalidInputError
from psorr.types import PointCloud

FRONT = np.column_stack([np.linspace(-0.3, 0.3, 12), np.zeros(12), np.full(12, 1.0)])


@pytest.mark.parametrize("width, height", [(-6, -2), (0, 0), (6.0, 2), (True, 12)])
def test_an_organised_size_must_be_whole_numbers_of_at_least_one(width, height):
    with pytest.raises(InvalidInputError, match="PointCloud.width"):
        PointCloud(FRONT, width=width, height=height)


def test_complex_or_boolean_coordinates_are_refused_not_cast():
    for points in (FRONT * (1 + 1j), FRONT > 0.5):
        with pytest.raises(InvalidInputError, match=f"points must be real numbers, got a {points.dtype.name} array"):
            PointCloud(points)
    assert PointCloud(FRONT.astype(np.float32)).points.dtype == np.float64


def test_labels_that_int64_would_change_are_refused():
    for labels in ([0.5] * 12, [np.nan] * 12, np.full(12, 2**64 - 1, np.uint64)):
        with pytest.raises(InvalidInputError, match="labels must be whole numbers"):
            PointCloud(FRONT, labels=labels)
    kept = PointCloud(FRONT, labels=np.arange(12, dtype=float) - 1).labels
    assert kept.dtype == np.int64 and kept.tolist() == list(range(-1, 11))


def test_normals_must_be_unit_vectors():
    colours = np.random.default_rng(0).integers(0, 255, (12, 3)).astype(float)  # RGB passed as normals
    with pytest.raises(InvalidInputError, match="normals must be unit vectors: 12 of 12 finite rows.*normals=None"):
        PointCloud(FRONT, normals=colours)
    up = np.tile([0.0, 0.0, -1.0], (12, 1))
    up[3] = np.nan  # an invalid pixel's normal is unknown, not wrong
    assert np.isnan(PointCloud(FRONT, normals=up).normals[3]).all()


def test_the_millimetre_check_sees_past_nan_rows_that_recur_with_the_stride():
    points = FRONT.repeat(100, axis=0) * 1000.0
    points[::97] = np.nan  # an organised cloud's invalid pixels can fall on every sampled row
    with pytest.raises(InvalidInputError, match="millimetres"):
        require_sensor_metres(PointCloud(points), "scene.npy")


def test_points_behind_the_sensor_or_too_wide_a_view_are_refused():
    require_seen_from_origin(PointCloud(FRONT), "ok")
    behind = FRONT.copy()
    behind[3, 2] = -0.2
    with pytest.raises(InvalidInputError, match="1 of its 12 finite points lie at z <= 0"):
        require_seen_from_origin(PointCloud(behind), "scene.npy")
    grazing = FRONT * [1.0, 1.0, 0.01]  # 30 cm wide at 1 cm: a world-frame table seen edge-on
    with pytest.raises(InvalidInputError, match="wider than any depth sensor's"):
        require_seen_from_origin(PointCloud(grazing), "scene.npy")


def test_a_single_stray_point_far_beyond_any_sensor_is_named_not_crashed_on():
    # One corrupt value 10 km off passed the median check and made a crop grid of 22 GiB.
    stray = np.vstack([FRONT, [[5000.0, 5000.0, 1e4]]])
    for check in (require_sensor_metres, require_seen_from_origin):
        with pytest.raises(InvalidInputError, match=r"scene.npy: 1 of its 13 finite points lie more than 1000 m"
                                                    r".*\(5000, 5000, 1e\+04\) m.*mark them NaN"):
            check(PointCloud(stray), "scene.npy")
    require_seen_from_origin(PointCloud(np.vstack([FRONT, [[300.0, 0.0, 900.0]]])), "ok")  # far, not absurd


def test_missing_depth_written_as_zeros_is_named_with_the_fix():
    zeros = np.vstack([FRONT, np.zeros((3, 3))])
    with pytest.raises(InvalidInputError, match=r"3 of its 15 finite points are exactly \(0, 0, 0\).*mark them NaN"):
        require_seen_from_origin(PointCloud(zeros), "scene.pcd")
