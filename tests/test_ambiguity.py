"""Near-symmetries (psorr/ambiguity.py): the chassis turned end for end is told from the chassis."""

import numpy as np
import pytest

from psorr.ambiguity import best_of_near_symmetries, near_symmetries
from psorr.library import ModelLibrary
from psorr.scenes import workpiece_scene
from psorr.verify import SceneView
from psorr.workpieces import load_catalog


@pytest.fixture(scope="module")
def parts(tmp_path_factory):
    import os

    os.environ["PSORR_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    catalog = load_catalog()
    names = ["bracket", "chassis"]
    library = ModelLibrary.from_meshes([catalog[n].mesh_path for n in names])
    return catalog, library, {n: catalog[n].load_mesh() for n in names}


def test_the_chassis_has_a_half_turn_about_its_height_and_the_bracket_none(parts):
    _, library, _ = parts
    chassis = library.model("chassis")
    turns = near_symmetries(chassis.points, chassis.diameter)
    assert len(turns) == 1
    axis_z = turns[0][:3, :3] @ [0.0, 0.0, 1.0]
    assert np.allclose(axis_z, [0.0, 0.0, 1.0], atol=0.05)  # a turn about z keeps z
    assert np.allclose(turns[0][:3, :3] @ [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], atol=0.05)
    bracket = library.model("bracket")
    assert len(near_symmetries(bracket.points, bracket.diameter)) == 0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_true_pose_wins_over_its_near_symmetric_twin(parts, seed):
    """Start from the chassis turned end for end: the dense check turns it back (the window and the
    gland hole are at the ends)."""
    _, library, meshes = parts
    scene = workpiece_scene(np.random.default_rng(seed), meshes, ["chassis"])
    chassis = library.model("chassis")
    turn = near_symmetries(chassis.points, chassis.diameter)
    T_true = scene.instances[0].T_camera_model
    T, check = best_of_near_symmetries(SceneView(scene.cloud), chassis, T_true @ turn[0], turn, 0.01)
    assert np.linalg.norm(T[:3, 3] - T_true[:3, 3]) < 0.005
    R = T[:3, :3].T @ T_true[:3, :3]
    assert np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))) < 3.0
    assert 0 < check.score <= 1
