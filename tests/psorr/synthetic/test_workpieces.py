"""Tests for the workpiece assets (meshes, catalog) and psorr.synthetic.catalog: sound, stable meshes,
true symmetries, grasps that fit and can be reached, the symmetric ADD, and a deterministic build."""

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
GRASPS = [(name, g.name) for name in NAMES for g in CATALOG[name].grasps]
# The gripper: a parallel jaw with box fingers; metres.
OPENING = 0.080  # widest finger separation
CLEARANCE = 0.005  # fingers open this far beyond each contact face before closing
FINGER_LENGTH = 0.045  # along the approach, fingertip to palm
FINGER_WIDTH = 0.016  # across both approach and closing
FINGER_THICKNESS = 0.008  # along closing
TIP_PAST_POINT = 0.005  # the pads are centred on the grasp point, so the tips reach this much further


@cache
def _mesh(name: str) -> trimesh.Trimesh:
    return CATALOG[name].load_mesh()


def _rot_z(deg: float) -> np.ndarray:
    c, s = np.cos(np.deg2rad(deg)), np.sin(np.deg2rad(deg))
    t = np.eye(4)
    t[:2, :2] = [[c, -s], [s, c]]
    return t


def _first_hits(mesh, origins, direction):
    """(N,) distance from each origin along `direction` to the first surface hit (inf: none), (N, 3) hit normals."""
    origins = np.atleast_2d(origins)
    directions = np.tile(direction, (len(origins), 1))
    locations, rays, triangles = mesh.ray.intersects_location(origins, directions, multiple_hits=True)
    distance = np.full(len(origins), np.inf)
    normal = np.zeros((len(origins), 3))
    for location, ray, triangle in zip(locations, rays, triangles):
        d = float((location - origins[ray]) @ direction)
        if d < distance[ray]:
            distance[ray], normal[ray] = d, mesh.face_normals[triangle]
    return distance, normal


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


def test_colours_and_grasp_names_are_distinct():
    colours = np.array([CATALOG[n].color for n in NAMES])
    gaps = np.linalg.norm(colours[:, None] - colours[None], axis=2) + np.eye(len(NAMES))
    assert gaps.min() > 0.1
    for name in NAMES:
        names = [g.name for g in CATALOG[name].grasps]
        assert len(set(names)) == len(names)


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
def test_every_part_has_a_grasp_the_gripper_can_hold(name):
    widths = [g.width for g in CATALOG[name].grasps]
    assert max(widths) <= OPENING - 2 * CLEARANCE
    assert any(0.010 <= w <= 0.070 for w in widths)


@pytest.mark.parametrize(("name", "grasp_name"), GRASPS)
def test_grasp_width_is_the_thickness_between_parallel_faces(name, grasp_name):
    mesh, grasp = _mesh(name), CATALOG[name].grasp(grasp_name)
    reach = grasp.width / 2 + CLEARANCE
    for side in (1.0, -1.0):
        start = grasp.point + side * reach * grasp.closing
        assert not mesh.contains([start])[0], "the open finger would start inside the part"
        distance, normal = _first_hits(mesh, start, -side * grasp.closing)
        # The contact face sits exactly width / 2 from the point and faces the finger.
        assert distance[0] == pytest.approx(CLEARANCE, abs=1e-5)
        assert normal[0] @ (side * grasp.closing) > 0.999


@pytest.mark.parametrize(("name", "grasp_name"), GRASPS)
def test_grasp_is_reachable_along_its_approach(name, grasp_name):
    mesh, grasp = _mesh(name), CATALOG[name].grasp(grasp_name)
    across = np.cross(grasp.approach, grasp.closing)
    reach = grasp.width / 2 + CLEARANCE
    far = 0.5  # start the rays well outside the part
    # Both fingers sweep down to their tips without touching the part...
    for side in (1.0, -1.0):
        tips = np.array(
            [
                grasp.point + side * (reach + t) * grasp.closing + u * across + TIP_PAST_POINT * grasp.approach
                for t in (0.0, FINGER_THICKNESS / 2, FINGER_THICKNESS)
                for u in (-FINGER_WIDTH / 2, 0.0, FINGER_WIDTH / 2)
            ]
        )
        assert np.all(tips[:, 2] >= 0.0), "a fingertip would hit the table"
        distance, _ = _first_hits(mesh, tips - far * grasp.approach, grasp.approach)
        assert np.all(distance > far), "a finger would collide with the part on the way in"
    # ...and nothing of the part between them rises to the palm.
    palm = np.array(
        [
            grasp.point + t * grasp.closing + u * across
            for t in np.linspace(-reach - FINGER_THICKNESS, reach + FINGER_THICKNESS, 9)
            for u in (-FINGER_WIDTH / 2, 0.0, FINGER_WIDTH / 2)
        ]
    )
    distance, _ = _first_hits(mesh, palm - far * grasp.approach, grasp.approach)
    assert np.all(far - distance < FINGER_LENGTH), "the part would hit the palm"


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
