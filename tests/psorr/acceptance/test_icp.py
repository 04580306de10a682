"""psorr.acceptance.icp: the damped point-to-plane ICP, and refine_icp on parts that leave motions unconstrained."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from psorr.acceptance.icp import point_to_plane, refine_icp
from psorr.library.models import ModelLibrary
from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.verification.scene_view import SceneView


def _corner(rng, n=3000):
    """Points (N, 3) and normals of three 10 cm faces meeting at the origin, like a box's corner."""
    u, v = rng.uniform(0, 0.1, (2, n))
    face = rng.integers(0, 3, n)
    points = np.zeros((n, 3))
    normals = np.zeros((n, 3))
    for k in range(3):
        mine = face == k
        points[mine, (k + 1) % 3], points[mine, (k + 2) % 3] = u[mine], v[mine]
        normals[mine, k] = 1.0
    return points, normals


def test_a_well_posed_fit_converges_to_the_true_motion():
    rng = np.random.default_rng(0)
    target, normals = _corner(rng)
    R = Rotation.from_rotvec(np.radians(3.0) * np.array([1.0, 2.0, 3.0]) / np.sqrt(14)).as_matrix()
    source = target[::3] @ R.T + [0.004, -0.003, 0.002]
    T = point_to_plane(source, target, normals, max_distance=0.012)
    moved = source @ T[:3, :3].T + T[:3, 3]
    assert np.abs(moved - target[::3]).max() < 3e-4


def test_a_half_cylinder_is_moved_onto_its_axis_but_not_along_it():
    # Sliding along the axis is free for a cylinder: the fit must not take it.
    rng = np.random.default_rng(1)
    n = 3000
    angle, x = rng.uniform(0, np.pi, n), rng.uniform(-0.055, 0.055, n)
    normals = np.column_stack([np.zeros(n), np.cos(angle), np.sin(angle)])
    target = 0.021 * normals + np.outer(x, [1.0, 0.0, 0.0])
    source = target[::3] + [0.0, 0.002, 0.0]
    T = point_to_plane(source, target, normals, max_distance=0.012)
    assert abs(T[1, 3] + 0.002) < 2e-4  # back onto the axis
    assert abs(T[0, 3]) < 1e-4  # and not along it


@pytest.mark.parametrize("skip_holes", [False, True], ids=["fine fit's points", "coarse fit's"])
@pytest.mark.parametrize("seed, name", [(3, "u_channel"), (2, "bushing")])
def test_refinement_stays_at_the_true_pose_of_a_partly_hidden_part(seed, name, skip_holes):
    # The peers benchmark's occluded clutter. From the true pose, recognition's coarse refinement (12 mm
    # pairs, 15 iterations) took the U-channel 0.47 diameters away (its points hidden by nearer parts
    # pulled it onto those), and the bushing 0.85 (Open3D's undamped steps ran away).
    assert _coarse_fit_from_truth(seed, name, skip_holes) < 0.1


@pytest.mark.parametrize("seed, name", [(2, "bushing"), (20, "flanged_hub")])
def test_coarse_refinement_leaves_out_the_sensor_holes_of_a_small_round_part(seed, name):
    # The sensors benchmark's Kinect clutter. The bushing's body and the hub's side, seen edge on, are
    # Kinect holes: half the visible model points have no measurement near their pixel and paired with the
    # flange and the table, and from the true pose the coarse refinement took the parts 5.3 and 11.6 mm off.
    assert _coarse_fit_from_truth(seed, name, skip_holes=True) < 0.04


def _coarse_fit_from_truth(seed: int, name: str, skip_holes: bool) -> float:
    """ADD, in model diameters, of recognition's coarse refinement (12 mm pairs, 15 iterations) of part ``name``
    from its true pose in the seeded 4-part clutter scene ``seed`` with the arm-sized occluder."""
    catalog = load_catalog()
    names = list(np.random.default_rng(seed).choice(sorted(catalog), size=4, replace=False))
    scene = workpiece_scene(np.random.default_rng(1000 + seed), {n: catalog[n].load_mesh() for n in names}, names,
                            occluder=True)
    instance = next(inst for inst in scene.instances if inst.name == name)
    model = ModelLibrary.from_meshes([catalog[name].mesh_path]).model(name)
    T = refine_icp(SceneView(scene.cloud), model.points, model.normals, instance.T_camera_model, 0.012,
                   iterations=15, max_points=1000, skip_holes=skip_holes)
    return symmetric_add(model.points[::10], T, instance.T_camera_model, catalog[name]) / model.diameter
