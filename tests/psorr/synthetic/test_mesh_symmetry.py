"""psorr.synthetic.mesh_symmetry: symmetries found from meshes built here with known symmetries, and from the
catalog's parts, whose symmetries the catalog lists; the symmetric ADD they grade with."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from part_meshes import box, cylinder, ellipsoid, flanged_bushing, l_bracket, plate_with_hole

from psorr.errors import InvalidInputError
from psorr.geometry.rotations import turn, turn_about_line
from psorr.synthetic.catalog import load_catalog, model_diameter, symmetric_add
from psorr.synthetic.mesh_symmetry import (
    MeshSymmetry,
    SymmetryParams,
    _closed_group,
    find_symmetries,
    mesh_symmetric_add,
)

CATALOG = load_catalog()


def _rotations(symmetry: MeshSymmetry) -> list[np.ndarray]:
    return [S[:3, :3] for S in symmetry.turns]


def _has_rotation(symmetry: MeshSymmetry, R: np.ndarray) -> bool:
    return any(np.allclose(Q, R, atol=1e-6) for Q in _rotations(symmetry))


def _pose(rng) -> np.ndarray:
    """A random camera-frame pose (4, 4) about 0.8 m in front."""
    T, axis = np.eye(4), rng.normal(size=3)
    T[:3, :3] = turn(axis / np.linalg.norm(axis), rng.uniform(0, np.pi))
    T[:3, 3] = rng.uniform(-0.2, 0.2, 3) + (0, 0, 0.8)
    return T


def test_a_box_of_three_sides_has_the_three_half_turns_about_its_axes():
    symmetry = find_symmetries(box((0.06, 0.04, 0.02)))
    assert len(symmetry.turns) == 4 and symmetry.axis is None
    for axis in np.eye(3):
        assert _has_rotation(symmetry, 2 * np.outer(axis, axis) - np.eye(3))
    assert np.allclose(symmetry.turns[0], np.eye(4))


def test_a_square_bar_has_its_quarter_turns_and_the_half_turns_across():
    symmetry = find_symmetries(box((0.03, 0.03, 0.08)))
    assert len(symmetry.turns) == 8  # the dihedral group of the square
    assert _has_rotation(symmetry, turn(np.array([0.0, 0.0, 1.0]), np.pi / 2))
    diagonal = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    assert _has_rotation(symmetry, 2 * np.outer(diagonal, diagonal) - np.eye(3))


def test_a_cylinder_turns_freely_about_its_axis_and_flips_end_for_end():
    symmetry = find_symmetries(cylinder())
    assert symmetry.axis is not None and abs(symmetry.axis[2]) == pytest.approx(1.0)
    assert len(symmetry.turns) == 2
    assert symmetry.turns[1][:3, :3] @ symmetry.axis @ symmetry.axis == pytest.approx(-1.0)


def test_a_ball_turns_every_way_and_only_its_centre_is_graded():
    ball = trimesh.creation.icosphere(subdivisions=4, radius=0.03)
    symmetry = find_symmetries(ball)
    assert symmetry.spherical and symmetry.axis is not None
    assert not find_symmetries(cylinder()).spherical
    rng = np.random.default_rng(7)
    points = ball.sample(500, seed=1)
    T_true, T_turned = _pose(rng), _pose(rng)
    T_turned[:3, 3] = T_true[:3, 3]  # turned every which way about the same centre: the same ball
    assert mesh_symmetric_add(points, T_turned, T_true, symmetry) == pytest.approx(0.0, abs=1e-6)
    T_turned[:3, 3] += (0.004, 0.0, 0.0)
    assert mesh_symmetric_add(points, T_turned, T_true, symmetry) == pytest.approx(0.004, abs=1e-5)


def test_a_long_faceted_rod_read_from_a_file_flips_without_closing_a_group(tmp_path, recwarn):
    # Its 64 side facets each give a half turn across the axis; composed, they spin it by every multiple of
    # 5.6 degrees, a group of hundreds whose products overflowed. One flip is all a continuous axis needs.
    trimesh.creation.cylinder(radius=0.004, height=0.15, sections=64).export(tmp_path / "rod.stl")
    symmetry = find_symmetries(trimesh.load(tmp_path / "rod.stl"))
    assert len(symmetry.turns) == 2 and abs(symmetry.axis[2]) == pytest.approx(1.0)
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_turns_within_the_tolerance_compose_only_into_turns_that_hold():
    # An exact half turn about y and one 1.8 degrees off it (both within a smooth part's tolerance) compose
    # into spins about x by 3.6 degrees and its multiples; only those that map the part onto itself join.
    flip, near = (turn_about_line(axis, np.pi, np.zeros(3)) for axis in ((0.0, 1.0, 0.0), (0.0, 0.9995, 0.0314)))
    exact_or_near = {0.0, 180.0}

    def holds(S):
        angle = np.degrees(np.arccos(np.clip((np.trace(S[:3, :3]) - 1) / 2, -1, 1)))
        return any(abs(angle - a) < 2.0 for a in exact_or_near)

    group = _closed_group([flip, near], np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]), 1e-4, holds)
    assert len(group) < 10 and all(holds(S) for S in group)


def test_a_gear_of_forty_teeth_closes_its_eighty_turns():
    # Its turns found about near axes compose into spins a fraction of a degree apart; unless those count as
    # one turn, they filled the group's cap of 200 (seconds to a minute of surface distances).
    spin = [trimesh.transformations.rotation_matrix(2 * np.pi * k / 40, (0.0, 0.0, 1.0)) for k in range(40)]
    teeth = [trimesh.creation.box(extents=(0.005, 0.0024, 0.01)).apply_translation((0.0305, 0.0, 0.0))
             .apply_transform(T) for T in spin]
    gear = trimesh.boolean.union([trimesh.creation.cylinder(radius=0.029, height=0.01, sections=240), *teeth])
    symmetry = find_symmetries(gear)
    assert symmetry.axis is None and len(symmetry.turns) == 80
    assert any(np.allclose(R, spin[1][:3, :3], atol=0.01) for R in _rotations(symmetry))  # by one tooth


def test_a_flanged_bushing_turns_freely_but_does_not_flip():
    symmetry = find_symmetries(flanged_bushing())
    assert symmetry.axis is not None and len(symmetry.turns) == 1


def test_an_l_bracket_swaps_equal_legs_about_their_bisector_only():
    symmetry = find_symmetries(l_bracket(0.05, 0.05))
    assert len(symmetry.turns) == 2
    bisector = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    assert _has_rotation(symmetry, 2 * np.outer(bisector, bisector) - np.eye(3))
    assert len(find_symmetries(l_bracket(0.06, 0.04)).turns) == 1  # unequal legs: none


def test_a_plate_with_an_off_centre_hole_keeps_only_the_half_turn_through_the_hole():
    symmetry = find_symmetries(plate_with_hole(offset=0.02))
    assert len(symmetry.turns) == 2
    assert _has_rotation(symmetry, np.diag([1.0, -1.0, -1.0]))
    S = symmetry.turns[1]
    assert np.allclose(S[:3, 3], 0.0, atol=1e-9)  # the line y = z = 0 holds the hole's centre


def test_an_ellipsoid_has_its_three_half_turns_and_no_axis():
    symmetry = find_symmetries(ellipsoid())
    assert len(symmetry.turns) == 4 and symmetry.axis is None


@pytest.mark.parametrize("name", sorted(CATALOG))
def test_the_catalog_parts_symmetries_are_found_from_their_meshes(name):
    """Grading with either set of symmetries gives the same verdicts: every catalog symmetry is one found, and
    every found one is one the catalog lists, for poses anywhere."""
    info, mesh = CATALOG[name], CATALOG[name].load_mesh()
    symmetry = find_symmetries(mesh)
    assert (symmetry.axis is None) == (info.continuous_axis is None)
    assert len(symmetry.turns) == len(info.symmetries)
    points = np.asarray(trimesh.sample.sample_surface(mesh, 500, seed=1)[0])
    tolerance = 0.01 * model_diameter(mesh)
    T = _pose(np.random.default_rng(3))
    for S in info.symmetries:
        assert mesh_symmetric_add(points, T @ S, T, symmetry) < tolerance
    for S in symmetry.symmetries[:: max(1, len(symmetry.symmetries) // 40)]:
        assert symmetric_add(points, T @ S, T, info) < tolerance


def test_the_symmetric_add_forgives_a_symmetry_and_nothing_else():
    mesh = plate_with_hole()
    symmetry = find_symmetries(mesh)
    points = np.asarray(trimesh.sample.sample_surface(mesh, 500, seed=1)[0])
    T = _pose(np.random.default_rng(0))
    assert mesh_symmetric_add(points, T @ symmetry.turns[1], T, symmetry) < 1e-6
    about_z = np.eye(4)
    about_z[:3, :3] = turn(np.array([0.0, 0.0, 1.0]), np.pi)  # the hole goes to the other end
    assert mesh_symmetric_add(points, T @ about_z, T, symmetry) > 0.1 * model_diameter(mesh)


def test_the_continuous_axis_is_searched_in_steps():
    mesh = cylinder()
    symmetry = find_symmetries(mesh)
    points = np.asarray(trimesh.sample.sample_surface(mesh, 500, seed=1)[0])
    T, spin = _pose(np.random.default_rng(2)), np.eye(4)
    spin[:3, :3] = turn(symmetry.axis, np.radians(37.0))
    assert mesh_symmetric_add(points, T @ spin, T, symmetry) < 0.01 * model_diameter(mesh)


def test_bad_input_says_what_to_give():
    with pytest.raises(InvalidInputError, match="trimesh.Trimesh"):
        find_symmetries(np.zeros((4, 3)))
    with pytest.raises(InvalidInputError, match="MeshSymmetry"):
        mesh_symmetric_add(np.zeros((3, 3)), np.eye(4), np.eye(4), CATALOG["bracket"])
    with pytest.raises(InvalidInputError, match="tolerance"):
        SymmetryParams(tolerance=2.0)
