"""psorr.decomposition.support_crop: the table far from the parts is left out of the decomposition."""

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from psorr.decomposition.support_crop import SupportCropParams, crop_to_parts, standing_bar
from psorr.errors import InvalidInputError
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.mesh_scenes import SceneParams, mesh_scene
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import PointCloud
from psorr.verification.scene_view import SceneView


def _scene(names, seed):
    catalog = load_catalog()
    return workpiece_scene(np.random.default_rng(seed), {n: catalog[n].load_mesh() for n in names}, names)


def test_far_table_is_blanked_and_every_part_point_kept_in_place():
    scene = _scene(["circuit_board"], 5)  # a thin board: only its components stand clear of the plane
    plane = SceneView(scene.cloud).support_plane
    margin = 0.09
    cropped = crop_to_parts(scene.cloud, plane, margin)
    before, after = np.isfinite(scene.cloud.points).all(axis=1), np.isfinite(cropped.points).all(axis=1)
    assert (cropped.width, cropped.height) == (scene.cloud.width, scene.cloud.height)
    assert not (after & ~before).any()
    np.testing.assert_array_equal(cropped.points[after], scene.cloud.points[after])  # nothing moved
    assert after.sum() < 0.2 * before.sum()  # most of a 640x480 frame is table
    # The whole board, its flat top included, and table out to the margin along the plane stay.
    surface, _ = trimesh.sample.sample_surface(load_catalog()["circuit_board"].load_mesh(), 5000, seed=0)
    T = scene.instances[0].T_camera_model
    gap, _ = cKDTree(surface @ T[:3, :3].T + T[:3, 3]).query(scene.cloud.points[before])
    assert (gap < 0.004).sum() > 500
    assert after[before][gap < 0.004].all()
    # Table out to the margin (along the plane, so at least that far in space) of anything off it stays.
    points = scene.cloud.points[before]
    off = np.abs(points @ plane[:3] + plane[3]) > SupportCropParams().off_plane
    reach, _ = cKDTree(points[off]).query(points)
    assert after[before][reach < margin].all()
    height = scene.cloud.points @ plane[:3] + plane[3]
    assert height[before & ~after].max() <= SupportCropParams().off_plane  # only the table, and what is under it
    assert not after[before & (height < -SupportCropParams().off_plane)].any()  # no part can be below the table


def test_a_far_table_seen_obliquely_is_cropped_for_its_noise_not_kept_for_it():
    # 1.3-1.4 m away and tilted 55-60 degrees, the table reaches 2 m, where the sensor's noise lifts hundreds of
    # its points past 8 mm: each would keep a band of table around it, and the whole frame was decomposed.
    catalog = load_catalog()
    params = SceneParams(camera_distance=(1.3, 1.4), camera_tilt_deg=(55.0, 60.0))
    scene = mesh_scene(np.random.default_rng(1), {"bushing": catalog["bushing"].load_mesh()}, "single",
                       names=["bushing"], params=params)
    plane = SceneView(scene.cloud).support_plane
    before = scene.cloud.valid_mask
    assert scene.cloud.points[before, 2].max() > 1.9
    after = crop_to_parts(scene.cloud, plane, 0.09).valid_mask
    assert after.sum() < 0.1 * before.sum()
    assert after[before & (scene.cloud.labels == 1)].all()  # the part stays whole
    bar = standing_bar(scene.cloud.points[before], plane, SupportCropParams())
    assert bar.min() == SupportCropParams().off_plane and bar.max() > 0.012  # the bar rises only where noise is
    assert (standing_bar(scene.cloud.points[before], plane, SupportCropParams(sensor_noise=False)) == 0.008).all()


def test_nothing_is_cropped_without_a_plane_or_when_disabled():
    scene = _scene(["bracket"], 3)
    plane = SceneView(scene.cloud).support_plane
    assert crop_to_parts(scene.cloud, None, 0.09) is scene.cloud
    assert crop_to_parts(scene.cloud, plane, 0.09, SupportCropParams(enabled=False)) is scene.cloud
    flat = PointCloud(np.column_stack([np.random.default_rng(0).uniform(-0.3, 0.3, (500, 2)), np.ones(500)]))
    assert crop_to_parts(flat, np.array([0.0, 0.0, -1.0, 1.0]), 0.09) is flat  # nothing stands on it


def test_bad_crop_settings_are_refused():
    with pytest.raises(InvalidInputError, match="off_plane"):
        SupportCropParams(off_plane=0.0)


@pytest.mark.parametrize("height", [0.0, 0.5])  # on the table's plane, and standing above it
def test_a_stray_point_far_along_the_table_changes_nothing_else(height):
    # The band was dilated on a grid over every point: one point 700 m off along both axes of the table
    # made it 70,000 cells on a side (5 GB). Now the grid spans what stands on the table, and a stray
    # point standing far off is looked up in a k-d tree instead.
    scene = _scene(["bracket"], 2)
    plane = SceneView(scene.cloud).support_plane
    finite = np.flatnonzero(np.isfinite(scene.cloud.points).all(axis=1))
    u = np.cross(plane[:3], [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    points = scene.cloud.points.copy()
    points[finite[0]] += 700.0 * (u + np.cross(plane[:3], u)) + height * plane[:3]
    expected = crop_to_parts(PointCloud(np.delete(scene.cloud.points, finite[0], axis=0)), plane, 0.09).points
    got = crop_to_parts(PointCloud(points), plane, 0.09).points
    np.testing.assert_array_equal(np.delete(got, finite[0], axis=0), expected)


def test_the_k_d_tree_band_equals_the_grid_band(monkeypatch):
    from psorr.decomposition import support_crop

    scene = _scene(["u_channel", "bushing"], 4)
    plane = SceneView(scene.cloud).support_plane
    on_grid = crop_to_parts(scene.cloud, plane, 0.09).points
    monkeypatch.setattr(support_crop, "_MAX_GRID_CELLS", 0)
    np.testing.assert_array_equal(crop_to_parts(scene.cloud, plane, 0.09).points, on_grid)
