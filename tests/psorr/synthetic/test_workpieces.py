"""Tests for the workpiece assets (meshes, catalog) and psorr.synthetic.catalog: sound, stable meshes,
true symmetries, the symmetric ADD, and a deterministic build. The catalog's grasps are the sim's
(tests/sim/skills/test_grasps.py)."""

from __future__ import annotations

import importlib.util
import json
import sys
from functools import cache

import numpy as np
import pytest
import trimesh
from scipy.spatial import Delaunay

from psorr.errors import InvalidInputError, PsorrError
from psorr.synthetic.catalog import (
    DEFAULT_CATALOG,
    CatalogError,
    get_workpiece,
    load_catalog,
    model_diameter,
    symmetric_add,
)

ASSETS = DEFAULT_CATALOG.parent
CATALOG = load_catalog()
NAMES = sorted(CATALOG)


@cache
def _mesh(name: str) -> trimesh.Trimesh:
    return CATALOG[name].load_mesh()


def _rot_z(deg: float) -> np.ndarray:
    c, s = np.cos(np.deg2rad(deg)), np.sin(np.deg2rad(deg))
    t = np.eye(4)
    t[:2, :2] = [[c, -s], [s, c]]
    return t


@pytest.mark.parametrize("name", NAMES)
def test_mesh_is_one_watertight_body_of_sensible_size(name):
    mesh = _mesh(name)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    assert mesh.body_count == 1
    assert np.all(mesh.extents > 0.005) and np.all(mesh.extents < 2.0)
    assert CATALOG[name].mesh_path.stat().st_size < 1_000_000


@pytest.mark.parametrize("name", NAMES)
def test_rests_stably_on_its_base_at_identity(name):
    mesh = _mesh(name)
    assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-7)
    base = mesh.vertices[mesh.vertices[:, 2] < 0.001, :2]
    assert Delaunay(base).find_simplex(mesh.center_mass[:2]) >= 0


@pytest.mark.parametrize("name", NAMES)
def test_mass_is_volume_times_density(name):
    entry = json.loads(DEFAULT_CATALOG.read_text())["parts"][name]
    assert CATALOG[name].mass == pytest.approx(_mesh(name).volume * entry["density"], rel=1e-4)


def test_colours_are_distinct():
    colours = np.array([CATALOG[n].color for n in NAMES])
    gaps = np.linalg.norm(colours[:, None] - colours[None], axis=2) + np.eye(len(NAMES))
    assert gaps.min() > 0.1


@pytest.mark.parametrize("name", NAMES)
def test_symmetries_map_the_mesh_onto_itself(name):
    mesh, info = _mesh(name), CATALOG[name]
    samples = trimesh.sample.sample_surface(mesh, 2000, seed=0)[0]
    transforms = list(info.symmetries)
    if info.continuous_axis is not None:
        transforms.append(trimesh.transformations.rotation_matrix(np.deg2rad(37.0), info.continuous_axis))
    for transform in transforms:
        moved = trimesh.transform_points(samples, transform)
        assert trimesh.proximity.closest_point(mesh, moved)[1].max() < 0.0005


@pytest.mark.parametrize("name", [n for n in NAMES if CATALOG[n].continuous_axis is None])
def test_a_non_symmetry_does_not_map_the_mesh_onto_itself(name):
    mesh = _mesh(name)
    samples = trimesh.sample.sample_surface(mesh, 2000, seed=0)[0]
    moved = trimesh.transform_points(samples, _rot_z(37.0))
    assert trimesh.proximity.closest_point(mesh, moved)[1].max() > 0.002


@pytest.mark.parametrize("name", NAMES)
def test_symmetric_add_is_zero_for_symmetric_poses_and_large_for_wrong_ones(name):
    info, mesh = CATALOG[name], _mesh(name)
    points = trimesh.sample.sample_surface(mesh, 500, seed=1)[0]
    T_true = trimesh.transformations.euler_matrix(0.3, -0.2, 1.1)
    T_true[:3, 3] = (0.1, -0.05, 0.8)
    for symmetry in info.symmetries:
        assert symmetric_add(points, T_true @ symmetry, T_true, info) < 1e-9
    if info.continuous_axis is not None:
        spin = trimesh.transformations.rotation_matrix(np.deg2rad(37.0), info.continuous_axis)
        assert symmetric_add(points, T_true @ spin, T_true, info) < 0.0005
    # Tilting the part 30 degrees about a horizontal axis is no symmetry of any part.
    tilt = trimesh.transformations.rotation_matrix(np.deg2rad(30.0), (1, 0, 0), mesh.center_mass)
    assert symmetric_add(points, T_true @ tilt, T_true, info) > 0.05 * model_diameter(mesh)


def test_symmetric_add_equals_plain_add_without_symmetries():
    info = CATALOG["chassis"]
    points = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]])
    shifted = np.eye(4)
    shifted[:3, 3] = (0.0, 0.003, 0.004)
    assert symmetric_add(points, shifted, np.eye(4), info) == pytest.approx(0.005)


def test_symmetric_add_rejects_bad_input():
    info = CATALOG["chassis"]
    with pytest.raises(InvalidInputError, match=r"\(N, 3\)"):
        symmetric_add(np.zeros((4, 2)), np.eye(4), np.eye(4), info)
    with pytest.raises(InvalidInputError, match="rigid"):
        symmetric_add(np.zeros((4, 3)), 2 * np.eye(4), np.eye(4), info)


def test_model_diameter():
    assert model_diameter(trimesh.creation.box((1.0, 2.0, 2.0))) == pytest.approx(3.0)
    assert model_diameter(np.array([[0.0, 0, 0], [0.3, 0.4, 0]])) == pytest.approx(0.5)
    with pytest.raises(InvalidInputError):
        model_diameter(np.zeros((1, 3)))


def test_catalog_errors_name_the_problem(tmp_path):
    with pytest.raises(CatalogError, match="not found"):
        load_catalog(tmp_path / "nowhere.json")
    bad = tmp_path / "catalog.json"
    bad.write_text("{not json")
    with pytest.raises(CatalogError, match="JSON"):
        load_catalog(bad)
    bad.write_text(json.dumps({"parts": {}}))
    with pytest.raises(CatalogError, match="parts"):
        load_catalog(bad)
    entry = json.loads(DEFAULT_CATALOG.read_text())["parts"]["bracket"]
    bad.write_text(json.dumps({"parts": {"bracket": {k: v for k, v in entry.items() if k != "mass"}}}))
    with pytest.raises(CatalogError, match="'mass'"):
        load_catalog(bad)
    bad.write_text(json.dumps({"parts": {"bracket": {**entry, "color": [2, 0, 0]}}}))
    with pytest.raises(CatalogError, match="color"):
        load_catalog(bad)
    bad.write_text(json.dumps({"parts": {"bracket": entry}}))  # its relative mesh path does not exist here
    with pytest.raises(CatalogError, match="does not exist"):
        load_catalog(bad)
    assert issubclass(CatalogError, PsorrError)


def test_unknown_workpiece_lists_the_valid_names():
    assert get_workpiece("bracket").name == "bracket"
    with pytest.raises(InvalidInputError, match="flanged_hub"):
        get_workpiece("sprocket")


def _build_module():
    path = ASSETS / "build_workpieces.py"
    spec = importlib.util.spec_from_file_location("build_workpieces", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve their module through sys.modules
    spec.loader.exec_module(module)
    return module


def test_build_is_deterministic_and_matches_the_committed_assets(tmp_path):
    build = _build_module()
    first, second = build.build_parts(), build.build_parts()
    assert list(first) == list(second) == list(CATALOG)
    for name in first:
        np.testing.assert_array_equal(first[name].mesh.vertices, second[name].mesh.vertices)
        np.testing.assert_array_equal(first[name].mesh.faces, second[name].mesh.faces)
    build.write_all(tmp_path)
    assert (tmp_path / "catalog.json").read_bytes() == DEFAULT_CATALOG.read_bytes(), "rerun the build script"
    for name in first:
        stl = f"meshes/{name}.stl"
        assert (tmp_path / stl).read_bytes() == (ASSETS / stl).read_bytes(), "rerun the build script"
