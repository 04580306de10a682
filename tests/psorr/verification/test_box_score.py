"""Batched box verification (psorr.verification.box_score) against the pair-by-pair definition it replaces."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from psorr.decomposition import DecomposeParams, decompose
from psorr.geometry.box_overlap import boxes_may_overlap, intersection_ratio
from psorr.hypotheses.primitive_match import RADIUS_TOLERANCE
from psorr.library.models import ModelLibrary
from psorr.synthetic.catalog import DEFAULT_CATALOG, load_catalog
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import OrientedBox, PrimitiveKind
from psorr.verification.box_score import PrimitiveArrays, box_scores

COS_20 = np.cos(np.radians(20.0))


def _one_by_one(model, T, scene_prims, thickness):
    """The definition, one hypothesis and one pair of boxes at a time."""
    R, covered, weights = T[:3, :3], [], []
    for p in model.graph.primitives:
        box = OrientedBox(R @ p.box.center + T[:3, 3], R @ p.box.rotation, p.box.extent)
        if p.kind is PrimitiveKind.PLANE and (R @ p.normal) @ box.center >= 0:
            continue  # faces away from the sensor
        best = 0.0
        for s in scene_prims:
            if s.kind is not p.kind:
                continue
            if p.kind is PrimitiveKind.PLANE:
                agree = (R @ p.normal) @ s.normal > COS_20
            else:
                agree = (abs((R @ p.axis) @ s.axis) > COS_20
                         and abs(p.radius - s.radius) < RADIUS_TOLERANCE * p.radius)
            if agree and boxes_may_overlap(box, s.box):  # boxes that meet, compared thickened
                best = max(best, intersection_ratio(box, s.box, thickness))
        covered.append(best)
        weights.append(p.n_points)
    return float(np.average(covered, weights=weights)) if weights else 0.0


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    import os

    os.environ["PSORR_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    meshes = DEFAULT_CATALOG.parent / "meshes"
    return ModelLibrary.from_meshes([meshes / "bracket.stl", meshes / "bushing.stl"])


def test_batched_scores_equal_the_one_by_one_definition(library):
    catalog = load_catalog()
    names = ["bracket", "bushing"]
    scene = workpiece_scene(np.random.default_rng(5), {n: catalog[n].load_mesh() for n in names}, names)
    decomposition = decompose(scene.cloud, DecomposeParams(voxel_size=0.008), np.random.default_rng(0))
    scene_prims = [p for p in decomposition.primitives if max(p.box.extent) < 0.3]  # not the table
    rng = np.random.default_rng(1)
    every = []
    for inst in scene.instances:
        model = library.model(inst.name)
        # Poses around the truth (near misses score between 0 and 1) and around the other part.
        poses = []
        for base in (inst.T_camera_model, scene.instances[0].T_camera_model):
            for _ in range(15):
                T = base.copy()
                T[:3, :3] = Rotation.from_rotvec(rng.normal(0, 0.15, 3)).as_matrix() @ T[:3, :3]
                T[:3, 3] += rng.normal(0, 0.01, 3)
                poses.append(T)
        poses = np.array(poses)
        batched = box_scores(PrimitiveArrays.of(model.graph.primitives), poses, PrimitiveArrays.of(scene_prims), 0.04)
        expected = [_one_by_one(model, T, scene_prims, 0.04) for T in poses]
        np.testing.assert_allclose(batched, expected, atol=1e-7)
        every.extend(batched)
    assert max(every) > 0.5 and min(every) == 0.0  # the poses span good, partial and missed overlaps


def test_no_poses_or_no_scene_primitives_score_nothing(library):
    model = PrimitiveArrays.of(library.model("bracket").graph.primitives)
    assert box_scores(model, np.zeros((0, 4, 4)), model, 0.04).shape == (0,)
    assert box_scores(model, np.eye(4)[None], PrimitiveArrays.of([]), 0.04).tolist() == [0.0]


def test_one_batch_of_several_models_scores_as_each_model_alone(library):
    catalog = load_catalog()
    names = ["bracket", "bushing"]
    scene = workpiece_scene(np.random.default_rng(5), {n: catalog[n].load_mesh() for n in names}, names)
    decomposition = decompose(scene.cloud, DecomposeParams(voxel_size=0.008), np.random.default_rng(0))
    scene_prims = PrimitiveArrays.of(p for p in decomposition.primitives if max(p.box.extent) < 0.3)
    models = [PrimitiveArrays.of(library.model(n).graph.primitives) for n in names]
    rng = np.random.default_rng(2)
    poses, owners = [], []
    for inst in scene.instances:
        for owner in (0, 1):  # each model at both parts' poses, interleaved
            for _ in range(6):
                T = inst.T_camera_model.copy()
                T[:3, :3] = Rotation.from_rotvec(rng.normal(0, 0.1, 3)).as_matrix() @ T[:3, :3]
                T[:3, 3] += rng.normal(0, 0.005, 3)
                poses.append(T)
                owners.append(owner)
    poses, owners = np.array(poses), np.array(owners)
    together = box_scores(models, poses, scene_prims, 0.04, owners)
    for m, model in enumerate(models):
        np.testing.assert_allclose(together[owners == m], box_scores(model, poses[owners == m], scene_prims, 0.04),
                                   atol=1e-12)
    assert together.max() > 0.5


def test_owners_must_index_the_models(library):
    from psorr.errors import InvalidInputError

    model = PrimitiveArrays.of(library.model("bracket").graph.primitives)
    with pytest.raises(InvalidInputError, match="owners must be"):
        box_scores([model], np.eye(4)[None], model, 0.04, np.array([1]))
