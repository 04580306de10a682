"""psorr.unexplained: what stands on the table and no detection explains, for recognition's second look."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from psorr.library import ModelLibrary
from psorr.scenes import OCCLUDER_LABEL, workpiece_scene
from psorr.types import Detection
from psorr.unexplained import blanked, part_sized, standing_points, standing_unexplained
from psorr.verify import SceneView
from psorr.workpieces import load_catalog

OFF_PLANE, REACH = 0.008, 0.006


@pytest.fixture(scope="module")
def parts(tmp_path_factory):
    import os

    os.environ["PSORR_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    catalog = load_catalog()
    names = ["bushing", "chassis"]
    library = ModelLibrary.from_meshes([catalog[n].mesh_path for n in names])
    return library, {n: catalog[n].load_mesh() for n in names}


def _trees(library):
    return {m.name: cKDTree(m.points) for m in library.models}


def test_a_detected_part_leaves_nothing_and_an_undetected_one_all_it_shows(parts):
    library, meshes = parts
    scene = workpiece_scene(np.random.default_rng(3), meshes, ["bushing", "chassis"])
    plane = SceneView(scene.cloud).support_plane
    bushing, chassis = scene.instances
    found = [Detection("chassis", chassis.T_camera_model, 0.9)]
    standing = standing_points(scene.cloud, plane, OFF_PLANE)
    rest = standing_unexplained(scene.cloud, standing, found, _trees(library), REACH)
    # The chassis' points are all explained; of the bushing's, all that stand clear of the table are not.
    height = scene.cloud.points @ plane[:3] + plane[3]
    on_bushing = scene.cloud.labels == 1
    assert rest[on_bushing & (height > 0.012)].all()
    assert rest[scene.cloud.labels == 2].mean() < 0.02
    assert not rest[height < OFF_PLANE].any()  # the table is never "unexplained"
    both = found + [Detection("bushing", bushing.T_camera_model, 0.9)]
    assert standing_unexplained(scene.cloud, standing, both, _trees(library), REACH).sum() < 60


def test_an_arm_across_the_table_is_not_part_sized_but_a_part_is(parts):
    _, meshes = parts
    scene = workpiece_scene(np.random.default_rng(1), {"bushing": meshes["bushing"]}, ["bushing"], occluder=True)
    plane = SceneView(scene.cloud).support_plane
    standing = standing_unexplained(scene.cloud, standing_points(scene.cloud, plane, OFF_PLANE), [], {}, REACH)
    kept = part_sized(scene.cloud, plane, standing, largest=0.19)
    assert kept[standing & (scene.cloud.labels == 1)].mean() > 0.95  # the bushing stays
    arm = standing & (scene.cloud.labels == OCCLUDER_LABEL)  # the capsule reaching across
    assert arm.sum() > 1000 and not kept[arm].any()
    assert not (kept & ~standing).any()


def test_explained_standing_points_are_blanked_and_the_table_kept(parts):
    library, meshes = parts
    scene = workpiece_scene(np.random.default_rng(3), meshes, ["bushing", "chassis"])
    plane = SceneView(scene.cloud).support_plane
    found = [Detection("chassis", scene.instances[1].T_camera_model, 0.9)]
    standing = standing_points(scene.cloud, plane, OFF_PLANE)
    rest = standing_unexplained(scene.cloud, standing, found, _trees(library), REACH)
    left = blanked(scene.cloud, standing & ~rest)
    kept = np.isfinite(left.points).all(axis=1)
    before = np.isfinite(scene.cloud.points).all(axis=1)
    height = scene.cloud.points @ plane[:3] + plane[3]
    assert (kept == (before & ((height <= OFF_PLANE) | rest))).all()
    np.testing.assert_array_equal(left.points[kept], scene.cloud.points[kept])
