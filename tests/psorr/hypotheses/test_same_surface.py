"""psorr.hypotheses.same_surface: poses of one model that put the same surface in the same place, on meshes
built here; and the resting search that keeps one of each."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from part_meshes import box, plate_with_hole, trained_library

from psorr.geometry.rotations import turn
from psorr.hypotheses.outline import OutlineMatcher, OutlineParams
from psorr.hypotheses.same_surface import SameSurface
from psorr.synthetic.mesh_scenes import mesh_scene
from psorr.verification.scene_view import SceneView

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")

PARTS = {"rod": trimesh.creation.cylinder(radius=0.006, height=0.12, sections=48), "bar": box((0.07, 0.03, 0.02)),
         "plate": plate_with_hole()}


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    return trained_library(PARTS, tmp_path_factory.mktemp("same_surface"))


def _pose(axis, degrees: float, shift=(0.0, 0.0, 0.0)) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = turn(np.asarray(axis, float), np.radians(degrees)), shift
    return T


def test_a_symmetry_between_two_poses_makes_them_one(library):
    same = SameSurface(library.models)
    rod, bar = library.names.index("rod"), library.names.index("bar")
    placed = _pose((1.0, 0.0, 0.0), 30.0, (0.1, 0.0, 0.8))
    assert same.same(rod, placed, placed @ _pose((0.0, 0.0, 1.0), 7.5))  # one side facet on: the same rod
    assert same.same(bar, placed, placed @ _pose((1.0, 0.0, 0.0), 180.0))  # the bar's half turn
    assert not same.same(bar, placed, placed @ _pose((1.0, 0.0, 0.0), 90.0))  # its long sides are not its short
    assert not same.same(rod, placed, placed @ _pose((0.0, 0.0, 1.0), 0.0, (0.004, 0.0, 0.0)))  # moved 4 mm


def test_the_plate_turned_about_its_hole_is_another_pose(library):
    same, plate = SameSurface(library.models), library.names.index("plate")
    # Its hole is off centre: the half turn about the normal through the centroid moves the hole.
    assert not same.same(plate, np.eye(4), _pose((0.0, 0.0, 1.0), 180.0))


@pytest.mark.parametrize("seed", [0, 1])
def test_a_rod_on_its_side_is_one_resting_pose_not_one_per_facet(library, seed):
    scene = mesh_scene(np.random.default_rng(seed), {"rod": PARTS["rod"]}, "single", names=["rod"])
    matcher = OutlineMatcher(library.models, OutlineParams())
    poses = matcher.candidates(scene.cloud, SceneView(scene.cloud)).candidates
    rod = [c for c in poses if c.model == library.names.index("rod")]
    assert rod and not any(matcher.same.same(a.model, a.T_cloud_model, b.T_cloud_model)
                           for k, a in enumerate(rod) for b in rod[k + 1:])
    assert len(rod) <= 4  # 48 side facets gave 24 poses of one rod
