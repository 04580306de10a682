"""Seeded scenes of CAD workpieces."""

import numpy as np
import pytest

from psorr.errors import InvalidInputError
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.workpiece_scenes import workpiece_scene

PARTS = ["transformer", "flanged_hub", "u_channel"]


@pytest.fixture(scope="module")
def meshes():
    catalog = load_catalog()
    return {name: catalog[name].load_mesh() for name in PARTS}


def test_instances_are_visible_where_their_pose_says(meshes):
    scene = workpiece_scene(np.random.default_rng(1), meshes, PARTS, noise=None)
    labels = scene.cloud.labels
    assert set(np.unique(labels)) <= {-1, 0, 1, 2, 3}
    for k, inst in enumerate(scene.instances, start=1):
        pts = scene.cloud.points[labels == k]
        assert len(pts) > 500, f"{inst.name} barely visible"
        # Noise-free points of an instance lie on its mesh placed at T_camera_model.
        local = (pts - inst.T_camera_model[:3, 3]) @ inst.T_camera_model[:3, :3]
        _, dist, _ = meshes[inst.name].nearest.on_surface(local[::50])
        assert dist.max() < 1e-4


def test_same_seed_same_cloud(meshes):
    a = workpiece_scene(np.random.default_rng(4), meshes, PARTS)
    b = workpiece_scene(np.random.default_rng(4), meshes, PARTS)
    assert np.array_equal(a.cloud.points, b.cloud.points, equal_nan=True)


def test_unknown_part_names_the_choices(meshes):
    with pytest.raises(InvalidInputError, match="choose from"):
        workpiece_scene(np.random.default_rng(0), meshes, ["gearbox"])


def test_occluding_capsule_hides_parts_and_keeps_the_layout(meshes):
    from psorr.synthetic.workpiece_scenes import OCCLUDER_LABEL

    bare = workpiece_scene(np.random.default_rng(1), meshes, PARTS, noise=None)
    hidden = workpiece_scene(np.random.default_rng(1), meshes, PARTS, noise=None, occluder=True)
    assert (hidden.cloud.labels == OCCLUDER_LABEL).sum() > 5000
    for k in range(1, len(PARTS) + 1):
        assert (hidden.cloud.labels == k).sum() <= (bare.cloud.labels == k).sum()
    for a, b in zip(bare.instances, hidden.instances):
        assert np.array_equal(a.T_camera_model, b.T_camera_model)  # the layout is drawn first
