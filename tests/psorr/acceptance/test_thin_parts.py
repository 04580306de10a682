"""A plate thinner than the depth tolerance, lying flat, is told from the bare table by render and compare
where its face stands a disparity step high (psorr/acceptance/thin_parts.py)."""

import numpy as np
import pytest
from part_meshes import plate_with_hole

from psorr.acceptance import thin_parts
from psorr.acceptance.params import AcceptParams
from psorr.acceptance.thin_parts import clear_of_table
from psorr.library.models import ModelLibrary
from psorr.sensing.kinect_noise import KINECT_V1
from psorr.synthetic.mesh_scenes import SceneParams, mesh_scene
from psorr.verification.depth_compare import DepthRenderer
from psorr.verification.point_check import check_pose, depth_tolerance
from psorr.verification.scene_view import SceneView

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")

NEED = AcceptParams().min_support_above_table
CHECK = AcceptParams().check


@pytest.fixture(scope="module")
def plate(tmp_path_factory):
    mesh = plate_with_hole(thickness=0.004)
    path = tmp_path_factory.mktemp("thin") / "plate.stl"
    mesh.export(path)
    return mesh, ModelLibrary.from_meshes([path], use_cache=False).model("plate")


def _judged(plate, distance, shift=(0.0, 0.0)):
    """(clear_of_table, the point check, depth tolerance, disparity step) of the 4 mm
    plate lying flat in a seeded scene, the camera ``distance`` m away, at its true pose moved ``shift``
    (x, y) m along the table."""
    mesh, model = plate
    params = SceneParams(camera_distance=(distance, distance), camera_tilt_deg=(20.0, 20.0))
    scene = mesh_scene(np.random.default_rng(0), {"plate": mesh}, "single", params=params)
    T_world_model = scene.T_world_camera @ scene.instances[0].T_camera_model
    T_world_model[:2, 3] += shift
    T_camera_model = np.linalg.inv(scene.T_world_camera) @ T_world_model
    view = SceneView(scene.cloud)
    check = check_pose(view, model.points, model.normals, T_camera_model, CHECK)
    z = np.array([T_camera_model[2, 3]])
    clear = clear_of_table(view, model, DepthRenderer(model.vertices, model.faces), T_camera_model, check, NEED,
                           CHECK)
    return clear, check, float(depth_tolerance(z, CHECK)[0]), \
        float(KINECT_V1.quantisation_step(z)[0])


def test_a_plate_under_the_tolerance_lying_where_it_is_seen_is_clear_of_the_table(plate):
    clear, check, tolerance, step = _judged(plate, 0.8)
    # The point count cannot see it; a disparity step can.
    assert step < 0.004 < tolerance and check.n_support_above_table < NEED
    assert clear


def test_the_same_plate_posed_on_bare_table_beside_it_is_not(plate):
    clear, check, _, _ = _judged(plate, 0.8, shift=(0.0, 0.12))
    assert check.n_support > 0.5 * check.n_visible > 100  # in view, and the table supports most of it
    assert not clear


def test_where_a_disparity_step_is_taller_than_the_plate_the_point_count_decides(plate, monkeypatch):
    # At 1.3 m a step is 5 mm: plate and table quantise to the same depths, whatever the averaging.
    clear, check, _, step = _judged(plate, 1.3)
    assert step > 0.004 and check.n_support_above_table < NEED
    assert not clear
    monkeypatch.setattr(thin_parts, "RESOLVABLE_STEPS", 0.0)  # the step, not the render, ruled it out
    assert _judged(plate, 1.3)[0]
