"""The ORR baseline: Papazov's budget, its own table of dense model pairs, and a part found through it."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
import trimesh

from psorr.errors import InvalidInputError
from psorr.hypotheses.orr import OrrParams, pairs_to_draw, papazov_iterations
from psorr.library.models import Model, ModelLibrary, TrainParams
from psorr.library.orr_table import OrrTable, OrrTableParams, surface_leaves
from psorr.recognize import Recognizer
from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import PrimitiveShapeGraph


@pytest.mark.parametrize(("success", "pair", "iterations"), [
    (0.99, 0.01, 459),     # ln 0.01 / ln 0.99 = 458.2
    (0.95, 0.05, 59),      # ln 0.05 / ln 0.95 = 58.4
    (0.99, 0.0125, 367),   # Papazov's implementation's defaults: 5% of the scene, p = 0.25: 366.1
    (0.5, 0.5, 1),         # one draw at even odds finds it with probability 0.5
    (0.99, 1.0, 1),
])
def test_budget_gives_the_textbook_numbers(success, pair, iterations):
    assert papazov_iterations(success, pair) == iterations
    assert 1 - (1 - pair) ** iterations >= success > 1 - (1 - pair) ** (iterations - 1) or iterations == 1


@pytest.mark.parametrize("bad", [(0.0, 0.1), (1.0, 0.1), (0.9, 0.0), (0.9, 1.5)])
def test_budget_refuses_what_is_not_a_probability(bad):
    with pytest.raises(InvalidInputError, match="P_S"):
        papazov_iterations(*bad)


def test_budget_scales_with_the_scene_over_the_smallest_model():
    table = SimpleNamespace(leaves=np.array([600, 2000]))
    params = OrrParams()
    # The smallest model's front half (300 leaves), 0.3 of it seen: 90 of the scene's 1000 leaves, each pair
    # landing on it with probability 0.09 x 0.25.
    share = params.min_visible * 600 / 2 / 1000
    expected = math.ceil(math.log(1 - 0.99) / math.log(1 - share * params.partner_probability))
    assert expected == 203 and pairs_to_draw(table, 1000, params) == 203
    assert pairs_to_draw(table, 4000, params) > 3 * 203  # a larger scene needs more pairs
    # A scene no larger than the instance is all instance: P_M = p, and ceil(ln 0.01 / ln 0.75) = 17 pairs,
    # but never more first points than the scene has.
    assert pairs_to_draw(table, 50, params) == 17 and pairs_to_draw(table, 10, params) == 10


def test_params_name_the_bad_field():
    with pytest.raises(InvalidInputError, match="OrrParams.success_probability"):
        OrrParams(success_probability=1.0)
    with pytest.raises(InvalidInputError, match="OrrTableParams.pair_width"):
        OrrTableParams(pair_width=1.5)


def _ellipsoid_model() -> Model:
    """A freeform part with no plane and no cylinder: an ellipsoid 60 x 40 x 30 mm, its graph empty."""
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    mesh.apply_scale([0.03, 0.02, 0.015])
    points, faces = trimesh.sample.sample_surface_even(mesh, 6000, seed=0)
    return Model("ellipsoid", np.asarray(points), mesh.face_normals[faces], PrimitiveShapeGraph(()), 0.06, "",
                 np.asarray(mesh.vertices), np.asarray(mesh.faces))


def test_a_model_without_primitives_gets_dense_pairs_from_its_surface():
    model = _ellipsoid_model()
    library = ModelLibrary.build([model], TrainParams())
    assert len(library.table) == 0  # PSORR's table pairs primitives, and this model has none
    params = OrrTableParams()
    table = OrrTable.for_library(library, params, use_cache=False)
    assert len(table) > 10_000
    leaves = table.table.points
    # One leaf per occupied voxel of the surface: about its area over a voxel's face, each on the surface.
    area = trimesh.Trimesh(model.vertices, model.faces).area
    assert 0.7 < len(leaves) * params.voxel_size**2 / area < 1.6
    # Every stored pair is the pair width apart, within the band.
    gap = np.linalg.norm(leaves[table.table.second] - leaves[table.table.first], axis=1)
    assert np.all(np.abs(gap - table.width) <= params.band + 1e-9)
    assert table.width == pytest.approx(params.pair_width * model.diameter)


def test_a_wall_thinner_than_a_voxel_gives_a_leaf_per_face():
    plate = trimesh.creation.box([0.05, 0.05, 0.002])
    points, faces = trimesh.sample.sample_surface_even(plate, 4000, seed=0)
    leaves, normals = surface_leaves(np.asarray(points), plate.face_normals[faces], 0.004)
    broad = np.abs(normals[:, 2]) > 0.9
    up, down = leaves[broad & (normals[:, 2] > 0)], leaves[broad & (normals[:, 2] < 0)]
    # Both faces, each leaf on its own face's side and facing out of it: the sensor sees either.
    assert len(up) > 100 and len(down) > 100
    assert up[:, 2].mean() > 0.0005 and down[:, 2].mean() < -0.0005


def test_orr_finds_a_part_with_its_own_table(library):
    catalog = load_catalog()
    name, seed = "bushing", 2011  # the peers benchmark's single-part scene of the bushing
    scene = workpiece_scene(np.random.default_rng(seed), {name: catalog[name].load_mesh()}, [name])
    recognizer = Recognizer(library, "orr")
    assert isinstance(recognizer.orr_table, OrrTable) and len(recognizer.orr_table) > 10 * len(library.table)
    result = recognizer.recognize(scene.cloud, np.random.default_rng(0))
    model, truth = library.model(name), scene.instances[0].T_camera_model
    assert any(d.model == name and symmetric_add(model.points[::10], d.T_cloud_model, truth, catalog[name])
               < 0.1 * model.diameter for d in result.detections)
    assert 0 < result.stats.hypotheses <= OrrParams().max_hypotheses
