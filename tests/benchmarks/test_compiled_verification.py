"""benchmarks/verify_compiled.py's compiled verifications compute what the library's numpy ones compute.

The benchmark's ratios mean something only if the compiled box scores and point checks are the same
computations: here on a seeded 3-part Kinect scene, at poses around the true ones and far off them.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
from paths import BENCHMARKS
from scipy.spatial.transform import Rotation

from psorr.decomposition import DecomposeParams, decompose
from psorr.geometry.rotations import from_rotation_vector
from psorr.hypotheses.primitive_match import RADIUS_TOLERANCE
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.verification.box_score import _COS_AGREE, PrimitiveArrays, _concatenated, box_scores
from psorr.verification.point_check import CheckParams, check_poses
from psorr.verification.scene_view import SceneView

sys.path.insert(0, str(BENCHMARKS))
import compiled_boxes  # noqa: E402
import compiled_points  # noqa: E402

PARTS = ["chassis", "flanged_hub", "bracket"]


@pytest.fixture(scope="module")
def scene(library):
    catalog = load_catalog()
    meshes = {name: catalog[name].load_mesh() for name in PARTS}
    return workpiece_scene(np.random.default_rng(3), meshes, PARTS, occluder=True)


@pytest.fixture(scope="module")
def poses(scene, library):
    """(P, 4, 4) poses and (P,) model indices: each part's true pose, nudged by up to 2 cm and 20
    degrees, and random poses in view."""
    rng = np.random.default_rng(0)
    out, owners = [], []
    for instance in scene.instances:
        for k in range(20):
            T = instance.T_camera_model.copy()
            if k:
                axis = rng.normal(size=3)
                turn = from_rotation_vector(axis / np.linalg.norm(axis) * np.radians(rng.uniform(0, 20)))
                T[:3, :3] = turn @ T[:3, :3]
                T[:3, 3] += rng.uniform(-0.02, 0.02, 3)
            out.append(T)
            owners.append(library.names.index(instance.name))
    centre = np.mean([i.T_camera_model[:3, 3] for i in scene.instances], axis=0)
    for R in Rotation.random(40, random_state=1).as_matrix():
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, centre + rng.uniform(-0.1, 0.1, 3)
        out.append(T)
        owners.append(int(rng.integers(len(library.models))))
    return np.array(out), np.array(owners, dtype=np.int64)


def test_box_scores_equal_the_librarys(scene, library, poses):
    models = [PrimitiveArrays.of(m.graph.primitives) for m in library.models]
    primitives = decompose(scene.cloud, DecomposeParams(voxel_size=0.008), np.random.default_rng(0)).primitives
    s = PrimitiveArrays.of(primitives)
    T, owners = poses
    expected = box_scores(models, T, s, 0.04, owners)
    lib, offsets = _concatenated(models)
    got = compiled_boxes.box_scores(lib.centers, lib.rotations, lib.extents, lib.is_plane, lib.direction,
                                    lib.radius, lib.weight, offsets, T, owners, s.centers, s.rotations, s.extents,
                                    s.is_plane, s.direction, s.radius, 0.04, _COS_AGREE, RADIUS_TOLERANCE)
    assert (expected > 0.3).sum() >= 3  # the nudged true poses score: the comparison is not all zeros
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_point_counts_equal_the_librarys(scene, library, poses):
    view = SceneView(scene.cloud)
    T, owners = poses
    models = library.models
    params = CheckParams()
    expected = check_poses(view, [models[m].points for m in owners], [models[m].normals for m in owners], T, params)
    offsets = np.r_[0, np.cumsum([len(m.points) for m in models])]
    got = compiled_points.check_poses(
        view.depth, view.nearby_depth, view.neighbour_depth, view.width, view.height, view.focal, view.cx, view.cy,
        np.asarray(view.support_plane, float), True, np.concatenate([m.points for m in models]),
        np.concatenate([m.normals for m in models]), offsets, owners, T, params.max_points, params.sigmas,
        params.min_tolerance)
    counts = np.array([(c.n_visible, c.n_support, c.n_violation, c.n_occluded, c.n_support_above_table)
                       for c in expected])
    assert (counts[:, 1] > 100).sum() >= 3
    np.testing.assert_array_equal(got, counts)
