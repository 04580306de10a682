"""Whether a mesh bounds a solid (psorr.geometry.solids), and what reading and resting make of one whose
bodies touch along an edge (closed, yet not what trimesh calls watertight)."""

import warnings

import numpy as np
import pytest
import trimesh

from psorr.geometry.solids import is_closed, open_edges, signed_volume
from psorr.io.meshes import read_mesh
from psorr.synthetic.resting import stable_rests

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")


def _touching_along_an_edge() -> trimesh.Trimesh:
    """A 10 mm cube and a 10 x 20 x 10 mm block sharing one vertical edge (four faces border it), metres."""
    cube = trimesh.creation.box((0.01, 0.01, 0.01))
    cube.apply_translation((0.005, 0.005, 0.005))
    block = trimesh.creation.box((0.01, 0.02, 0.01))
    block.apply_translation((0.015, 0.02, 0.005))
    mesh = trimesh.util.concatenate([cube, block])
    mesh.merge_vertices()
    return mesh


def test_bodies_touching_along_an_edge_bound_a_solid():
    mesh = _touching_along_an_edge()
    assert not mesh.is_watertight and is_closed(mesh) and open_edges(mesh) == 0
    assert mesh.volume == pytest.approx(3e-6)


def test_faces_collapsed_onto_a_vertex_leave_a_solid_closed():
    # An STL's 32-bit coordinates can put two corners of a sliver on one vertex: the face (a, a, b) has no
    # area and no way round, and the file was refused as wound against itself.
    box = trimesh.creation.box()
    a, b = box.faces[0][:2]
    collapsed = trimesh.Trimesh(box.vertices, np.vstack([box.faces, [a, a, b], [b, a, a]]), process=False)
    assert is_closed(collapsed) and open_edges(collapsed) == 0


def test_a_hole_or_a_face_wound_against_its_neighbours_bounds_none():
    holed = trimesh.creation.box()
    holed.update_faces(np.arange(len(holed.faces)) != 0)
    assert not is_closed(holed) and open_edges(holed) == 3
    flipped = trimesh.creation.box()
    flipped.faces[0] = flipped.faces[0][::-1]
    assert not is_closed(flipped) and open_edges(flipped) == 0


def test_such_a_part_is_read_without_a_word_and_rests_on_its_own_centre_of_mass(tmp_path):
    mesh = _touching_along_an_edge()
    mesh.export(tmp_path / "pair.stl")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read = read_mesh(tmp_path / "pair.stl")
    # Its rests are those of its own centre of mass (over the larger block), not its convex hull's.
    assert not np.allclose(read.center_mass, read.convex_hull.center_mass, atol=1e-4)
    _, expected = trimesh.poses.compute_stable_poses(read, center_mass=read.center_mass)
    found = [rest.probability for rest in stable_rests(read)]
    assert sorted(found) == pytest.approx(sorted(expected), abs=1e-6)


def test_a_sheet_on_a_solid_is_open_and_read_with_a_warning_not_refused(tmp_path):
    box = trimesh.creation.box((0.04, 0.03, 0.02))
    a, b = box.edges_unique[0]
    fin = np.append(box.vertices, [box.vertices[a] + (0.0, 0.0, 0.03)], axis=0)  # a fin on one of its edges
    finned = trimesh.Trimesh(fin, np.append(box.faces, [[a, b, len(box.vertices)]], axis=0), process=False)
    assert not is_closed(finned) and open_edges(finned) == 3  # the edge it shares (three faces), and its own two
    finned.export(tmp_path / "finned.stl")
    with pytest.warns(UserWarning, match="finned.stl: the mesh is not closed"):
        read_mesh(tmp_path / "finned.stl")


def test_the_signed_volume_is_the_enclosed_volume_and_negative_inside_out():
    box = trimesh.creation.box(extents=(0.02, 0.03, 0.04))
    assert signed_volume(box) == pytest.approx(0.02 * 0.03 * 0.04, rel=1e-12)
    inside_out = box.copy()
    inside_out.invert()
    assert signed_volume(inside_out) == pytest.approx(-0.02 * 0.03 * 0.04, rel=1e-12)
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.05)
    assert signed_volume(ball) == pytest.approx(ball.volume, rel=1e-12)
