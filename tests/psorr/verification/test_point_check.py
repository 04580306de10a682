"""psorr.verification.point_check: many poses checked in one pass give each the counts it gets alone."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from psorr.errors import InvalidInputError
from psorr.library.models import ModelLibrary
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.verification.point_check import CheckParams, check_pose, check_poses
from psorr.verification.scene_view import SceneView


@pytest.fixture(scope="module")
def scene_and_models():
    catalog = load_catalog()
    names = ["chassis", "bushing", "bracket", "u_channel"]
    scene = workpiece_scene(np.random.default_rng(12), {n: catalog[n].load_mesh() for n in names}, names,
                            occluder=True)
    library = ModelLibrary.from_meshes([catalog[n].mesh_path for n in names])
    return scene, library


def _counts(check):
    return check.n_visible, check.n_support, check.n_violation, check.n_occluded, check.supported_blocks.tolist()


def test_a_batch_of_poses_of_several_models_gives_each_pose_its_own_check(scene_and_models):
    scene, library = scene_and_models
    view = SceneView(scene.cloud)
    rng = np.random.default_rng(0)
    poses, models = [], []
    for instance in scene.instances:
        for spread in (0.0, 0.05, 0.3, 1.0):  # the truth, nearly, roughly, and far off (into the table too)
            T = instance.T_camera_model.copy()
            T[:3, :3] = Rotation.from_rotvec(rng.normal(0, spread, 3)).as_matrix() @ T[:3, :3]
            T[:3, 3] += rng.normal(0, 0.03 * spread, 3)
            poses.append(T)
            # Another model at the same pose too: its counts must not leak into the first's.
            models += [library.model(instance.name), library.model(scene.instances[0].name)]
            poses.append(T)
    params = CheckParams(max_points=400)
    batch = check_poses(view, [m.points for m in models], [m.normals for m in models], np.array(poses), params)
    alone = [check_pose(view, m.points, m.normals, T, params) for m, T in zip(models, poses)]
    assert [_counts(c) for c in batch] == [_counts(c) for c in alone]
    # The order of a batch does not matter either.
    order = rng.permutation(len(poses))
    shuffled = check_poses(view, [models[k].points for k in order], [models[k].normals for k in order],
                           np.array(poses)[order], params)
    assert [_counts(c) for c in shuffled] == [_counts(batch[k]) for k in order]
    # The true poses pass, and what was checked covers every kind of verdict.
    assert all(batch[8 * k].score > 0.5 for k in range(len(scene.instances)))
    assert sum(c.n_violation for c in batch) > 0 and sum(c.n_occluded for c in batch) > 0


def test_an_empty_batch_and_a_pose_facing_away_give_empty_checks(scene_and_models):
    scene, library = scene_and_models
    view = SceneView(scene.cloud)
    model = library.model("bushing")
    assert check_poses(view, [], [], np.empty((0, 4, 4))) == []
    behind = np.eye(4)
    behind[2, 3] = -1.0  # behind the sensor: nothing projects
    check = check_poses(view, [model.points], [model.normals], behind[None])[0]
    assert (check.n_visible, check.score, len(check.supported_blocks)) == (0, 0.0, 0)


def test_mismatched_poses_and_models_are_refused(scene_and_models):
    scene, library = scene_and_models
    view = SceneView(scene.cloud)
    model = library.model("bushing")
    with pytest.raises(InvalidInputError, match=r"poses \(P, 4, 4\)"):
        check_poses(view, [model.points], [model.normals], np.eye(4))
    with pytest.raises(InvalidInputError, match="2 point and 1 normal arrays"):
        check_poses(view, [model.points] * 2, [model.normals], np.stack([np.eye(4)] * 2))


def test_a_fine_buffer_numbers_only_the_self_occlusion_cells_in_use(scene_and_models, monkeypatch):
    # A dense unorganised cloud has a fine depth buffer: poses x blocks would not fit in memory.
    import psorr.verification.point_check as point_check

    scene, library = scene_and_models
    view = SceneView(scene.cloud)
    models = [library.model(i.name) for i in scene.instances]
    poses = np.array([i.T_camera_model for i in scene.instances])
    args = ([m.points for m in models], [m.normals for m in models], poses)
    direct = check_poses(view, *args)
    monkeypatch.setattr(point_check, "_MAX_CELLS", 10)
    assert [_counts(c) for c in check_poses(view, *args)] == [_counts(c) for c in direct]


def test_support_the_table_explains_as_well_is_not_counted_above_it():
    # A circuit board is 1.6 mm thick: posed flat anywhere on a bare table, its face is supported by the
    # table. Only its components, at the true pose, stand higher than the depth tolerance.
    from psorr.acceptance.params import AcceptParams

    catalog = load_catalog()
    library = ModelLibrary.from_meshes([catalog["circuit_board"].mesh_path])
    board = library.model("circuit_board")
    needed = AcceptParams().min_support_above_table
    for seed in range(2):
        scene = workpiece_scene(np.random.default_rng(seed), {"circuit_board": catalog["circuit_board"].load_mesh()},
                                ["circuit_board"])
        view = SceneView(scene.cloud)
        T_true = scene.instances[0].T_camera_model
        true = check_pose(view, board.points, board.normals, T_true)
        assert true.n_support_above_table > 4 * needed and true.n_support_above_table < true.n_support
        for dx in (-0.15, 0.15):  # slid along the table, onto bare table
            T_world_shift = np.eye(4)
            T_world_shift[0, 3] = dx
            T_slid = np.linalg.inv(scene.T_world_camera) @ T_world_shift @ scene.T_world_camera @ T_true
            slid = check_pose(view, board.points, board.normals, T_slid)
            assert slid.n_support > 400 and slid.n_support_above_table < needed / 2, (seed, dx, slid)


def test_the_rim_of_a_true_pose_is_not_seen_through_but_a_pose_over_the_table_is(scene_and_models):
    # A point on a part's rim falls on the pixel beside it as often as on its own, where the sensor sees
    # the table behind: seen through counts only where no neighbouring pixel measured the part either.
    scene, library = scene_and_models
    view = SceneView(scene.cloud)
    for instance in scene.instances:
        model = library.model(instance.name)
        truth = check_pose(view, model.points, model.normals, instance.T_camera_model)
        assert truth.violation_ratio <= 0.05, instance.name
    model = library.model("bushing")
    lifted = scene.instances[[i.name for i in scene.instances].index("bushing")].T_camera_model.copy()
    lifted[:3, 3] -= 0.05 * lifted[:3, 3] / np.linalg.norm(lifted[:3, 3])  # 5 cm nearer the sensor: in free space
    assert check_pose(view, model.points, model.normals, lifted).violation_ratio > 0.5
