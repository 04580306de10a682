"""Near-symmetric turns of parts made inside the test: a three-lobed knob's thirds, a box's half turns, a
three-spoked knob's half turns about each spoke, a drilled cube's turns of its hole onto its other axes."""

import numpy as np
import trimesh
from part_meshes import drilled_cube, spoked_knob, trained_library

from psorr.geometry.rotations import rotation_angle, rotation_vector
from psorr.library.symmetries import composed_turns, near_symmetries


def _samples(mesh: trimesh.Trimesh, count: int = 6000) -> tuple[np.ndarray, float]:
    points, _ = trimesh.sample.sample_surface_even(mesh, count, seed=0)
    return np.asarray(points), float(np.linalg.norm(mesh.extents))


def _three_lobed_knob() -> trimesh.Trimesh:
    """A 12 mm disc with three 8 mm lobes 120 degrees apart, and a 2 mm key on one lobe that makes the
    thirds near-symmetries rather than exact ones."""
    parts = [trimesh.creation.cylinder(radius=0.012, height=0.01, sections=48)]
    for k in range(3):
        a = 2.0 * np.pi * k / 3
        lobe = trimesh.creation.cylinder(radius=0.008, height=0.01, sections=32)
        lobe.apply_translation([0.014 * np.cos(a), 0.014 * np.sin(a), 0.0])
        parts.append(lobe)
    key = trimesh.creation.box([0.002, 0.002, 0.004])
    key.apply_translation([0.02, 0.0, 0.007])
    return trimesh.util.concatenate(parts + [key])


def test_a_three_lobed_knob_turns_by_thirds_about_its_axis():
    points, diameter = _samples(_three_lobed_knob())
    turns = near_symmetries(points, diameter)
    thirds = [S for S in turns if abs(np.degrees(rotation_angle(S[:3, :3])) - 120.0) < 5.0]
    assert len(thirds) == 2  # by 120 and by 240 degrees
    for S in thirds:
        assert np.allclose(S[:3, :3] @ [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], atol=0.05)  # about the axis, z


def test_a_box_of_three_different_sides_has_half_turns_only():
    points, diameter = _samples(trimesh.creation.box([0.06, 0.045, 0.03]))
    turns = near_symmetries(points, diameter)
    assert len(turns) == 3
    assert all(abs(np.degrees(rotation_angle(S[:3, :3])) - 180.0) < 3.0 for S in turns)


def test_a_square_bar_turns_by_quarters_about_its_length():
    points, diameter = _samples(trimesh.creation.box([0.03, 0.03, 0.08]))
    angles = sorted(round(np.degrees(rotation_angle(S[:3, :3]))) for S in near_symmetries(points, diameter))
    assert angles.count(90) == 2  # by 90 and by 270 degrees about its length


def test_a_three_spoked_knob_turns_over_about_every_spoke():
    """Its half turns about the spokes are near-symmetries (a 1 mm slot breaks them); no principal axis need lie
    along a spoke, so the search about its principal axes may miss some, and their products with the thirds
    are the others."""
    points, diameter = _samples(spoked_knob())
    turns = near_symmetries(points, diameter)
    more = composed_turns(turns, np.zeros(len(turns), dtype=bool), points, diameter)
    half_turn_axes = [v / np.linalg.norm(v) for v in (rotation_vector(S[:3, :3]) for S in np.concatenate([turns, more]))
                      if abs(np.degrees(np.linalg.norm(v)) - 180.0) < 5.0]
    for k in range(3):
        spoke = [np.cos(2 * np.pi * k / 3), np.sin(2 * np.pi * k / 3), 0.0]
        assert sum(abs(float(a @ spoke)) > 0.99 for a in half_turn_axes) == 1
    assert len(np.concatenate([turns, more])) == 5  # and the two thirds about its axis


def test_products_of_exact_symmetries_are_not_tried():
    points, diameter = _samples(trimesh.creation.box([0.03, 0.03, 0.08]))
    turns = near_symmetries(points, diameter)
    assert len(composed_turns(turns, np.ones(len(turns), dtype=bool), points, diameter)) == 0


def test_a_drilled_cubes_twins_put_its_hole_along_each_other_axis(tmp_path):
    """The cube's principal axes are any three, so turns about them miss most of its near-symmetries; about its
    faces' normals all 16 are found, and one of each that the exact symmetries make alike is kept: the hole
    across the view one way, and the other."""
    from psorr.acceptance.ambiguity import NearSymmetryResolver

    model = trained_library({"drilled_cube": drilled_cube()}, tmp_path).models[0]
    turns = NearSymmetryResolver(model).turns
    hole = model.graph.primitives[[p.kind.name for p in model.graph.primitives].index("CYLINDER")].axis
    moved = sorted(np.argmax(np.abs(S[:3, :3] @ hole)) for S in turns)
    assert len(turns) == 2 and moved == sorted({0, 1, 2} - {int(np.argmax(np.abs(hole)))})


def _hex_standoff() -> trimesh.Trimesh:
    """A hexagonal standoff, 19 mm across flats and 35 mm long, bored 10 mm, with a 4 mm cross hole near one end
    that makes its end for end half turns near-symmetries."""
    prism = trimesh.creation.cylinder(radius=0.011, height=0.035, sections=6)
    bore = trimesh.creation.cylinder(radius=0.005, height=0.05, sections=48)
    cross = trimesh.creation.cylinder(radius=0.002, height=0.03, sections=24)
    cross.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    cross.apply_translation([0.0, 0.0, 0.011])
    return prism.difference(bore).difference(cross)


def test_turns_come_best_fitting_first_so_that_the_best_stands_for_those_alike(tmp_path):
    """The standoff's section is round in its second moments, so its principal axes across it are any two, and a
    half turn about one settled 5.7 degrees off the face it stood for; the turns about the faces' normals fit
    better. Of turns alike up to a symmetry, the first kept stands for all (distinct_up_to_exact)."""
    from scipy.spatial import cKDTree

    from psorr.acceptance.ambiguity import _directions

    model = trained_library({"standoff": _hex_standoff()}, tmp_path).models[0]
    turns = near_symmetries(model.points, model.diameter, axis=np.array([0.0, 0.0, 1.0]), directions=_directions(model))
    tree, subset = cKDTree(model.points), model.points[:: max(1, len(model.points) // 3000)]  # as it measures them
    fits = [tree.query(subset @ S[:3, :3].T + S[:3, 3])[0].mean() for S in turns]
    assert len(turns) >= 4 and fits == sorted(fits)
