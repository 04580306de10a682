"""psorr.synthetic.resting: stable rests of meshes built here, and layouts without overlap."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from part_meshes import box, l_bracket

from psorr.errors import InvalidInputError
from psorr.synthetic import resting
from psorr.synthetic.resting import _separated, draw_rest, place_footprints, stable_rests

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")


def test_a_box_rests_on_its_faces_most_often_on_its_largest():
    rests = stable_rests(box((0.06, 0.04, 0.02)))
    assert sum(r.probability for r in rests) == pytest.approx(1.0)
    assert rests[0].height == pytest.approx(0.02) and rests[0].probability == max(r.probability for r in rests)
    assert sorted({round(r.height, 6) for r in rests}) == [0.02, 0.04, 0.06]


def test_each_rest_touches_the_table_and_centres_its_footprint():
    mesh = l_bracket(0.06, 0.04)
    for rest in stable_rests(mesh):
        on_table = mesh.vertices @ rest.T_table_model[:3, :3].T + rest.T_table_model[:3, 3]
        assert on_table[:, 2].min() == pytest.approx(0.0, abs=1e-12)
        assert np.ptp(on_table[:, 2]) == pytest.approx(rest.height)
        assert np.allclose(rest.footprint.mean(axis=0), 0.0, atol=1e-12)
        assert np.allclose(np.linalg.det(rest.T_table_model[:3, :3]), 1.0)


def test_a_finely_tessellated_round_part_rests_on_its_side_or_its_end():
    # Each of a 2048-sided cylinder's side facets is a rest of its own: trimesh's stable poses, superlinear in
    # the hull's faces, take its hull simplified (resting.HULL_FACES), and the rests stay the cylinder's.
    mesh = trimesh.creation.cylinder(radius=0.01, height=0.08, sections=2048)
    assert len(mesh.convex_hull.faces) > resting.HULL_FACES
    rests = stable_rests(mesh)
    assert len(rests) <= 2 * resting.SUPPORT_DIRECTIONS
    lying = [r for r in rests if r.height == pytest.approx(0.02, rel=0.01)]
    standing = [r for r in rests if r.height == pytest.approx(0.08, rel=0.01)]
    assert len(lying) + len(standing) == len(rests)
    assert sum(r.probability for r in lying) > sum(r.probability for r in standing) > 0
    for rest in rests:  # on the table, on the part's own vertices
        on_table = mesh.vertices @ rest.T_table_model[:3, :3].T + rest.T_table_model[:3, 3]
        assert on_table[:, 2].min() == pytest.approx(0.0, abs=1e-4)


def test_rests_are_drawn_by_their_probability():
    rests = stable_rests(box((0.06, 0.04, 0.02)))
    rng = np.random.default_rng(0)
    drawn = [draw_rest(rng, rests).height for _ in range(2000)]
    flat = np.mean(np.isclose(drawn, 0.02))
    assert flat == pytest.approx(sum(r.probability for r in rests if np.isclose(r.height, 0.02)), abs=0.04)


def test_rests_that_tie_come_in_one_order_however_trimesh_lists_them(monkeypatch):
    """A symmetric part's rests tie in probability but for the last bits, which need not be the same on
    another CPU; their order must not hang on those bits."""
    import trimesh

    mesh = box((0.06, 0.04, 0.02))  # each face and its opposite: three pairs of tied rests
    listed = trimesh.poses.compute_stable_poses(mesh)
    monkeypatch.setattr(resting, "_RESTS", {})
    first = [r.T_table_model for r in stable_rests(mesh)]
    # Listed the other way round, each probability off in the last bits as on another CPU.
    jitter = 1.0 + 1e-12 * np.arange(len(listed[1]))[::-1]
    monkeypatch.setattr(trimesh.poses, "compute_stable_poses",
                        lambda *_, **__: (listed[0][::-1], np.asarray(listed[1])[::-1] * jitter))
    monkeypatch.setattr(resting, "_RESTS", {})
    again = [r.T_table_model for r in stable_rests(mesh)]
    assert len(first) == 6 and all(np.allclose(a, b) for a, b in zip(first, again))


def _outlines(footprints, places):
    out = []
    for footprint, (x, y, yaw) in zip(footprints, places):
        c, s = np.cos(yaw), np.sin(yaw)
        out.append(footprint @ np.array([[c, s], [-s, c]]) + (x, y))
    return out


def test_footprints_are_laid_out_inside_the_patch_and_apart():
    squares = [np.array([(-a, -a), (a, -a), (a, a), (-a, a)]) for a in (0.05, 0.04, 0.03, 0.03, 0.02, 0.02)]
    places = place_footprints(np.random.default_rng(1), squares, (0.18, 0.18), gap=0.01)
    outlines = _outlines(squares, places)
    assert all(np.abs(o).max(axis=0).max() <= 0.18 + 1e-12 for o in outlines)
    for i in range(len(outlines)):
        for j in range(i + 1, len(outlines)):
            assert _separated(outlines[i], outlines[j], 0.01)


def test_too_much_for_the_patch_is_refused_with_the_fix():
    squares = [np.array([(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)])] * 5
    with pytest.raises(InvalidInputError, match="patch_half_extents"):
        place_footprints(np.random.default_rng(0), squares, (0.18, 0.18), gap=0.01, attempts=2)


def test_separation_sees_overlap_and_gaps():
    unit = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])
    assert not _separated(unit, unit + 0.5, 0.0)
    assert _separated(unit, unit + (1.2, 0.0), 0.1)
    assert not _separated(unit, unit + (1.2, 0.0), 0.3)
