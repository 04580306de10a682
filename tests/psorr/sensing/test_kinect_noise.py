"""The Kinect v1 noise model and depth back-projection."""

from __future__ import annotations

import numpy as np
import pytest

from psorr.errors import InvalidInputError
from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, project
from psorr.sensing.kinect_noise import (
    KINECT_V1,
    KinectNoise,
    apply_kinect_noise,
    grazing_angles,
    kinect_noise_with_source,
    shadow_mask,
)

K = CameraIntrinsics.kinect_v1()


def only(**switches) -> KinectNoise:
    """The model with every effect and the range limit off except those named."""
    off = dict.fromkeys(("axial", "lateral", "quantise", "grazing", "edges", "shadow"), False)
    return KinectNoise(**{**off, "depth_range": None, **switches})


def step_image(z_fg=0.7, z_bg=1.0, cols=(300, 400), rows=(150, 330)) -> np.ndarray:
    depth = np.full(K.shape, z_bg)
    depth[rows[0]:rows[1], cols[0]:cols[1]] = z_fg
    return depth


def tilted_plane(angle_deg: float, z0: float = 1.0) -> np.ndarray:
    """Depth of a plane through (0, 0, z0) whose normal is turned angle_deg about y."""
    n = np.array([np.sin(np.radians(angle_deg)), 0.0, np.cos(np.radians(angle_deg))])
    return z0 * n[2] / (K.pixel_rays() @ n)


@pytest.mark.parametrize("z", [0.8, 1.5])
def test_noise_statistics_match_the_model(z):
    depth = np.full(K.shape, z)
    noisy = apply_kinect_noise(depth, K, np.random.default_rng(1))
    error = noisy[noisy > 0] - z
    assert error.size > 0.99 * depth.size  # a flat fronto-parallel plane keeps its returns
    step = KINECT_V1.quantisation_step(z, K.fx)
    expected = np.sqrt(KINECT_V1.axial_sigma(z) ** 2 + step**2 / 12)
    assert abs(error.std() / expected - 1.0) < 0.2
    assert abs(error.mean()) < 0.05 * expected


@pytest.mark.parametrize("angle, z0", [(0.0, 0.8), (55.0, 1.4)])
def test_height_sigma_is_the_spread_of_a_planes_points_about_it(angle, z0):
    # Seen obliquely, depth noise moves a point along its ray, partly within the plane, and lateral jitter
    # reads a neighbouring ray's depth: the spread over the plane is what both give, not the depth's.
    depth = tilted_plane(angle, z0)
    noisy = apply_kinect_noise(depth, K, np.random.default_rng(2), only(axial=True, lateral=True, quantise=True))
    cloud = depth_to_cloud(noisy, K)
    points = cloud.points[cloud.valid_mask]
    normal = np.array([np.sin(np.radians(angle)), 0.0, np.cos(np.radians(angle))])
    height = points @ normal - z0 * normal[2]
    sigma = KINECT_V1.height_sigma(points, normal, K.fx)
    assert abs(np.std(height / sigma) - 1.0) < 0.1
    if angle:
        assert np.median(sigma) < 0.8 * np.median(KINECT_V1.depth_sigma(points[:, 2], K.fx))


def test_quantisation_gives_discrete_disparities():
    depth = np.broadcast_to(np.linspace(0.6, 1.2, K.width), K.shape)
    noisy = apply_kinect_noise(depth, K, np.random.default_rng(0), only(quantise=True, axial=True))
    levels = K.fx * KINECT_V1.baseline / noisy[noisy > 0] / KINECT_V1.disparity_step_px
    np.testing.assert_allclose(levels, np.rint(levels), atol=1e-6)
    assert len(np.unique(noisy)) < 400
    step = KINECT_V1.quantisation_step(1.0, K.fx)
    assert step == pytest.approx(1.0 / (8 * 525 * 0.075))


def test_same_seed_same_output_and_different_seed_differs():
    depth = tilted_plane(40.0)
    a = apply_kinect_noise(depth, K, np.random.default_rng(7))
    b = apply_kinect_noise(depth, K, np.random.default_rng(7))
    c = apply_kinect_noise(depth, K, np.random.default_rng(8))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a is not depth and np.all(depth > 0)  # the input is left alone


def test_dropouts_at_a_depth_edge():
    depth = step_image()
    noisy = apply_kinect_noise(depth, K, np.random.default_rng(3), only(edges=True))
    border = np.zeros(K.shape, bool)
    border[150:330, [299, 300, 399, 400]] = True
    border[[149, 150, 329, 330], 300:400] = True
    dropped = noisy == 0
    assert 0.3 < dropped[border].mean() < 0.7
    assert not dropped[~border].any()


def test_shadow_band_lies_on_the_side_away_from_the_projector():
    depth = step_image(z_fg=0.7, z_bg=1.0)
    noisy = apply_kinect_noise(depth, K, np.random.default_rng(0), only(shadow=True))
    width = K.fx * 0.075 * (1 / 0.7 - 1 / 1.0)  # 16.9 px
    row = noisy[240]
    shadow = np.flatnonzero(row == 0)
    assert shadow.max() == 299 and abs(len(shadow) - width) <= 1.0  # left of the object
    assert np.all(row[400:] > 0) and np.all(row[300:400] == 0.7)
    assert not (noisy[:150] == 0).any()  # rows without a foreground are untouched
    flipped = shadow_mask(depth, K, baseline=-0.075)[240]  # projector on the -x side
    assert flipped[400:420].sum() == len(shadow) and not flipped[:300].any()


def test_grazing_angle_dropouts():
    depth = tilted_plane(70.0, z0=0.8)  # the view angle runs from ~40 deg (right) to ~90 (left)
    angles = grazing_angles(depth, K)
    assert angles[240, 319:321].mean() == pytest.approx(70.0, abs=0.1)
    dropped = apply_kinect_noise(depth, K, np.random.default_rng(0), only(grazing=True)) == 0
    assert not dropped[angles < 75.0].any()
    assert dropped[angles > 85.0].all()
    ramp = (angles > 78.0) & (angles < 82.0)
    assert 0.25 < dropped[ramp].mean() < 0.75


def test_lateral_jitter_resamples_nearby_pixels_and_reports_the_source():
    depth = np.broadcast_to(np.arange(K.width, dtype=float) * 0.001 + 1.0, K.shape)
    noisy, source = kinect_noise_with_source(depth, K, np.random.default_rng(2), only(lateral=True))
    np.testing.assert_array_equal(noisy, depth.ravel()[source])
    cols = np.arange(K.width)[None, :]
    assert np.abs(source % K.width - cols).max() <= 4
    assert 0.2 < (source % K.width != cols).mean() < 0.45


def test_out_of_range_and_missing_depth_give_no_return():
    depth = np.full(K.shape, 1.0)
    depth[:10] = 0.0
    depth[10:20] = np.nan
    depth[20:30] = 5.0
    noisy = apply_kinect_noise(depth, K, np.random.default_rng(0), only(depth_range=(0.4, 4.0)))
    assert (noisy[:30] == 0).all() and (noisy[30:] == 1.0).all()


def test_parameters_are_checked():
    with pytest.raises(InvalidInputError):
        KinectNoise(edge_prob=1.5)
    with pytest.raises(InvalidInputError):
        KinectNoise(grazing_start_deg=80, grazing_end_deg=70)
    with pytest.raises(InvalidInputError):
        apply_kinect_noise(np.ones((10, 10)), K, np.random.default_rng(0))


def test_depth_to_cloud_back_projects_pixels():
    depth = np.full(K.shape, 0.8)
    depth[0, 0] = 0.0
    depth[0, 1] = np.nan
    labels = np.arange(depth.size).reshape(K.shape)
    cloud = depth_to_cloud(depth, K, labels=labels)
    assert cloud.is_organised and (cloud.width, cloud.height) == (640, 480)
    valid = cloud.valid_mask
    assert not valid[:2].any() and valid[2:].all()
    np.testing.assert_array_equal(cloud.labels[:2], [-1, -1])
    np.testing.assert_allclose(cloud.points[valid, 2], 0.8)
    u, v = 100, 50
    expected = [(u - 319.5) * 0.8 / 525.0, (v - 239.5) * 0.8 / 525.0, 0.8]
    np.testing.assert_allclose(cloud.points[v * K.width + u], expected, atol=1e-12)
    assert cloud.labels[v * K.width + u] == v * K.width + u
    np.testing.assert_allclose(project(cloud.points[[v * K.width + u]], K), [[u, v]], atol=1e-9)
    first = K.project(cloud.points[valid])[:3]
    np.testing.assert_allclose(first, [[2, 0], [3, 0], [4, 0]], atol=1e-9)
    with pytest.raises(InvalidInputError):
        depth_to_cloud(np.ones((4, 4)), K)


def test_a_noisier_sensor_scales_the_axial_noise_only():
    assert KINECT_V1.noisier(1) is KINECT_V1
    twice = KINECT_V1.noisier(2.0)
    z = np.array([0.6, 1.0, 1.6])
    np.testing.assert_allclose(twice.axial_sigma(z), 2 * KINECT_V1.axial_sigma(z))
    np.testing.assert_allclose(twice.quantisation_step(z), KINECT_V1.quantisation_step(z))
    with pytest.raises(InvalidInputError, match="above 0"):
        KINECT_V1.noisier(0.0)
