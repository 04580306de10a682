"""Thinning a cloud sampled finer than the sensor the thresholds suit (psorr.sensing.resolution)."""

import numpy as np
import pytest
import trimesh

from psorr import DecomposeParams, PointCloud, decompose
from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, look_at
from psorr.sensing.kinect_noise import kinect_noise_with_source
from psorr.sensing.raycast import render_meshes
from psorr.sensing.resolution import FINER_BY, thin_to_focal
from psorr.verification.scene_view import SceneView


def _sensor(scale: float) -> CameraIntrinsics:
    """A Kinect v1's field of view with `scale` times its pixels along each side."""
    width, height = round(640 * scale), round(480 * scale)
    return CameraIntrinsics(width=width, height=height, fx=525.0 * scale, fy=525.0 * scale,
                            cx=(width - 1) / 2, cy=(height - 1) / 2)


def _box_on_table(scale: float, seed: int) -> PointCloud:
    """A 12 cm box on a 60 cm table, 0.9 m from a sensor looking down at 40 degrees, with Kinect noise."""
    table = trimesh.creation.box((0.6, 0.6, 0.02))
    table.apply_translation((0, 0, -0.01))
    box = trimesh.creation.box((0.12, 0.08, 0.1))
    box.apply_transform(trimesh.transformations.rotation_matrix(0.4, (0, 0, 1)))
    box.apply_translation((0.02, -0.03, 0.05))
    camera = look_at((0.0, -0.69, 0.58), (0.0, 0.0, 0.0))
    intrinsics = _sensor(scale)
    depth, _ = render_meshes([(table, 0), (box, 1)], camera, intrinsics)
    noisy, _ = kinect_noise_with_source(depth, intrinsics, np.random.default_rng(seed))
    return depth_to_cloud(noisy, intrinsics)


def test_a_kinect_cloud_passes_unchanged():
    cloud = _box_on_table(1, 0)
    thinned = thin_to_focal(cloud, 525.0)
    assert thinned.cloud is cloud and not thinned.thinned
    stripped = PointCloud(cloud.points[cloud.valid_mask])
    assert thin_to_focal(stripped, 525.0).points_per_cell < FINER_BY


def test_a_grid_the_checks_read_at_its_own_pitch_passes_unchanged():
    cloud = _box_on_table(910.0 / 525.0, 0)  # a 1280x720 sensor's pitch: 3 points a Kinect pixel
    thinned = thin_to_focal(cloud, 525.0)
    assert thinned.cloud is cloud and not thinned.thinned
    # The same points unorganised are counted pixel by pixel, to the same verdict.
    stripped = thin_to_focal(PointCloud(cloud.points[cloud.valid_mask]), 525.0)
    assert not stripped.thinned and stripped.points_per_cell == pytest.approx(3.0, rel=0.1)


def test_a_cloud_twice_as_fine_is_thinned_to_a_kinects_count():
    kinect, fine = _box_on_table(1, 0), _box_on_table(2, 0)
    thinned = thin_to_focal(fine, 525.0)
    assert thinned.thinned and thinned.points_per_cell == pytest.approx(4.0, rel=0.1)
    assert len(thinned.kept) == pytest.approx(kinect.valid_mask.sum(), rel=0.05)
    image = thinned.cloud
    # Each kept point keeps its depth, moved onto its pixel's central ray: at most half a pixel.
    assert np.array_equal(image.points[image.valid_mask, 2], fine.points[thinned.kept, 2])
    shift = np.linalg.norm(image.points[image.valid_mask] - fine.points[thinned.kept], axis=1)
    assert shift.max() <= 0.5 * np.sqrt(2) / 525.0 * fine.points[thinned.kept, 2].max() + 1e-9
    # An image at the Kinect's pixel pitch (over what the points span), which the checks read as a camera's.
    assert image.is_organised and image.width <= 640 and image.height <= 480
    assert SceneView(image).focal == pytest.approx(525.0, rel=0.01)


def test_the_nearest_surface_of_a_direction_is_kept():
    # A table sampled under a box as well (a cloud merged from two views): a sensor sees only the box there.
    rng = np.random.default_rng(0)
    table = np.column_stack([rng.uniform(-0.05, 0.05, (40_000, 2)), np.full(40_000, 1.0)])
    # Over all the table's viewing directions and a little more, about 15 points a direction cell.
    box_top = np.column_stack([rng.uniform(-0.054, 0.054, (60_000, 2)), np.full(60_000, 0.9)])
    thinned = thin_to_focal(PointCloud(np.vstack([table, box_top])), 525.0)
    assert thinned.thinned
    kept_z = thinned.cloud.points[thinned.cloud.valid_mask, 2]
    assert np.all(np.abs(kept_z - 0.9) < 1e-9)


def test_nan_rows_are_not_kept_and_labels_follow():
    cloud = _box_on_table(2, 1)
    labels = np.arange(len(cloud.points))
    thinned = thin_to_focal(PointCloud(cloud.points, labels=labels), 525.0)
    image = thinned.cloud
    assert np.array_equal(image.labels[image.valid_mask], thinned.kept)
    assert (image.labels[~image.valid_mask] == -1).all()
    assert cloud.valid_mask[thinned.kept].all()


def _faces(result, n_points: int) -> list:
    """The planes holding at least 2% of the points, largest first. Strips of a few voxels along the box's
    edges come and go with the noise's draw at any density."""
    planes = [p for p in result.primitives if p.n_points >= 0.02 * n_points]
    return sorted(planes, key=lambda p: -p.n_points)


def test_the_same_scene_decomposes_alike_at_one_and_four_times_the_points():
    kinect, fine = _box_on_table(1, 0), _box_on_table(2, 0)
    coarse = _faces(decompose(kinect, rng=np.random.default_rng(0)), kinect.valid_mask.sum())
    result = decompose(fine, rng=np.random.default_rng(0))
    assert result.stats.n_sampled == pytest.approx(kinect.valid_mask.sum(), rel=0.05)
    dense = _faces(result, fine.valid_mask.sum())
    assert len(coarse) == len(dense) == 4  # the table and three faces of the box
    for a, b in zip(coarse, dense):
        normal_a, normal_b = np.asarray(a.params[:3]), np.asarray(b.params[:3])
        assert np.degrees(np.arccos(min(1.0, normal_a @ normal_b))) < 2.0
        assert abs(normal_b @ a.centroid + b.params[3]) < 0.003
        # Every point is labelled, not only the sampled ones: each face holds about four times the points.
        assert b.n_points == pytest.approx(4 * a.n_points, rel=0.2)


def test_cad_samples_are_never_thinned():
    cloud = _box_on_table(2, 0)
    params = DecomposeParams(sensor_noise=False, min_inlier_distance=0.004)
    assert decompose(cloud, params, np.random.default_rng(0)).stats.n_sampled == cloud.valid_mask.sum()
