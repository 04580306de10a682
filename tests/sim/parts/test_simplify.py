"""sim.parts.simplify: the mesh CoACD searches, fewer faces within a tolerance of the part."""

import numpy as np
import pytest
import trimesh

from sim.parts.simplify import simplified


def _fine_cylinder():
    # 40 mm across, 30 mm tall, 512 sides: a CAD export's fillet-fine tessellation of a plain shape.
    return trimesh.creation.cylinder(radius=0.02, height=0.03, sections=512)


def _distances(a: trimesh.Trimesh, b: trimesh.Trimesh) -> np.ndarray:
    points, _ = trimesh.sample.sample_surface(a, 5000, seed=1)
    return np.abs(trimesh.proximity.signed_distance(b, points))


def test_a_finely_tessellated_part_is_searched_with_fewer_faces_within_the_tolerance():
    part = _fine_cylinder()
    fewer = simplified(part, tolerance=0.0005)
    assert fewer is not None and len(fewer.faces) <= len(part.faces) // 4
    assert fewer.is_watertight
    assert _distances(part, fewer).max() <= 0.0005 and _distances(fewer, part).max() <= 0.0005
    np.testing.assert_allclose(fewer.bounds, part.bounds, atol=0.0005)


def test_a_tighter_tolerance_keeps_more_faces():
    part = _fine_cylinder()
    loose, tight = simplified(part, tolerance=0.001), simplified(part, tolerance=0.00002)
    assert loose is not None
    assert tight is None or len(tight.faces) > len(loose.faces)


def test_the_same_mesh_gives_the_same_faces():
    first, second = simplified(_fine_cylinder(), 0.0005), simplified(_fine_cylinder(), 0.0005)
    np.testing.assert_array_equal(first.vertices, second.vertices)
    np.testing.assert_array_equal(first.faces, second.faces)


def test_coarse_or_open_meshes_are_searched_as_they_are():
    assert simplified(trimesh.creation.box((0.05, 0.04, 0.03)), 0.001) is None
    open_cylinder = _fine_cylinder()
    open_cylinder.update_faces(np.arange(len(open_cylinder.faces)) != 0)
    assert not open_cylinder.is_watertight
    assert simplified(open_cylinder, 0.001) is None


def test_triangles_folded_against_the_part_are_measured_by_their_share_of_the_surface():
    from sim.parts.simplify import _distance_scene, _folded_share

    part = _fine_cylinder()
    folded = part.copy()
    flip = np.zeros(len(part.faces), bool)
    flip[::10] = True
    folded.faces[flip] = folded.faces[flip][:, ::-1]
    share = _folded_share(folded, part, _distance_scene(part))
    assert share == pytest.approx(folded.area_faces[flip].sum() / folded.area, abs=0.02)
    assert _folded_share(part, part, _distance_scene(part)) < 0.005
