"""psorr.hypotheses.standing_patches: what a patch's standing points say about the face they were measured on."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from part_meshes import trained_library

from psorr.hypotheses.outline import OutlineMatcher, OutlineParams
from psorr.hypotheses.standing_patches import Patch
from psorr.synthetic.mesh_scenes import SceneParams, mesh_scene
from psorr.verification.scene_view import SceneView

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")


def _plate(radius: float, thickness: float, sections: int, hole: float) -> trimesh.Trimesh:
    outer = trimesh.creation.cylinder(radius=radius, height=thickness, sections=sections)
    inner = trimesh.creation.cylinder(radius=hole, height=3 * thickness, sections=32)
    return trimesh.boolean.difference([outer, inner], engine="manifold")


# A 3.5 mm disc and a 5 mm hexagon a little smaller: 0.9 m away, where a point must stand 3.7 mm high, the
# disc stands only where the noise lifts it, and those points lie about as high as the hexagon's face.
PARTS = {"disc": _plate(0.025, 0.0035, 64, 0.006), "hexagon": _plate(0.023, 0.005, 6, 0.005)}


@pytest.mark.parametrize("height", [0.0, 0.0035, 0.005, 0.02])
def test_the_lift_is_how_far_the_standing_points_of_a_face_lie_above_it(height):
    patch = Patch(np.zeros((1, 3)), None, 0.006, bar=0.0042, height_sigma=0.0021)
    measured = height + np.random.default_rng(0).normal(0.0, 0.0021, 400_000)
    standing = measured[measured > 0.0042]
    assert patch.lift(height) == pytest.approx(standing.mean() - height, abs=1e-4)


def test_a_face_far_above_the_bar_or_without_noise_is_not_lifted():
    assert Patch(np.zeros((1, 3)), None, 0.006, bar=0.0042, height_sigma=0.0021).lift(0.03) < 1e-9
    assert Patch(np.zeros((1, 3)), None, 0.006).lift(0.002) == 0.0


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    return trained_library(PARTS, tmp_path_factory.mktemp("standing"))


@pytest.mark.parametrize("seed", range(4))
def test_a_thin_disc_far_from_the_sensor_fits_its_patch_better_than_a_thicker_smaller_plate(library, seed):
    params = SceneParams(camera_distance=(0.9, 0.9), camera_tilt_deg=(20.0, 20.0))
    scene = mesh_scene(np.random.default_rng(seed), PARTS, "single", names=["disc"], params=params)
    found = OutlineMatcher(library.models, OutlineParams()).candidates(scene.cloud, SceneView(scene.cloud))
    assert found.candidates and library.names[found.candidates[0].model] == "disc"
