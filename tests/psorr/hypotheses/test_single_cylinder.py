"""Poses from one cylinder (psorr.hypotheses.single_cylinder): a pipe tee whose branch gives no cylinder is still
found."""

import numpy as np
import pytest

from psorr.errors import InvalidInputError
from psorr.geometry.rotations import from_rotation_vector
from psorr.hypotheses.outline import OutlineParams
from psorr.hypotheses.single_cylinder import SingleCylinderMatcher, SingleCylinderParams, axis_frame, cylinder_length
from psorr.library.models import ModelLibrary
from psorr.recognize import RecognizeParams, Recognizer
from psorr.sensing.camera import CameraIntrinsics
from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import OrientedBox, Primitive, PrimitiveKind

# Occluded clutter scenes (seeds of the peers' clutter draw, benchmarks/peer_common.clutter_scene) in which
# the pipe tee's run came out of the decomposition as one cylinder and its branch as planar strips or not at
# all: no pair of primitives voted for the tee. Measured: missed without poses from one cylinder, found with
# them (of the 45 scenes with a tee among seeds 0-79, these two; seed 28's, once one of them, is found
# without them since the second look's narrower band, docs/decisions/0064-the-second-looks-band.md).
ONE_CYLINDER_TEES = (23, 54)


@pytest.fixture(scope="module")
def parts(tmp_path_factory):
    import os

    os.environ["PSORR_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    catalog = load_catalog()
    library = ModelLibrary.from_meshes([catalog[n].mesh_path for n in sorted(catalog)])
    return catalog, library


def _moved(cylinder: Primitive, T: np.ndarray) -> Primitive:
    """``cylinder`` as the pose T (4, 4) places it."""
    R, t = T[:3, :3], T[:3, 3]
    box = cylinder.box
    params = np.r_[R @ cylinder.axis_point + t, R @ cylinder.axis, cylinder.radius]
    return Primitive(PrimitiveKind.CYLINDER, tuple(params), cylinder.inliers, R @ cylinder.centroid + t,
                     OrientedBox(R @ np.asarray(box.center) + t, R @ box.rotation, box.extent))


def _tee_run(library) -> Primitive:
    """The pipe tee model's run: its widest, longest cylinder (110 mm long, 21 mm in radius)."""
    return max((p for p in library.model("pipe_tee").graph.primitives if p.kind is PrimitiveKind.CYLINDER),
               key=lambda p: (p.radius, cylinder_length(p)))


def test_a_cylinder_frame_sits_on_its_axis(parts):
    _, library = parts
    run = _tee_run(library)
    assert round(cylinder_length(run) * 1e3) == 110 and round(run.radius * 1e3) == 21
    towards = np.array([0.3, -0.2, 0.5])
    F = axis_frame(run, towards)
    assert np.allclose(F[:3, :3].T @ F[:3, :3], np.eye(3), atol=1e-9) and np.linalg.det(F[:3, :3]) > 0
    assert np.allclose(F[:3, 2], run.axis)
    middle = F[:3, 3]
    assert np.linalg.norm(np.cross(middle - run.axis_point, run.axis)) < 1e-9  # on the axis
    assert (towards - middle) @ F[:3, 0] > 0 and abs((towards - middle) @ F[:3, 1]) < 1e-9


def test_a_cylinder_seen_whole_gives_the_pose_to_within_half_a_roll_step(parts):
    catalog, library = parts
    model = library.model("pipe_tee")
    run = _tee_run(library)
    truth = np.eye(4)
    truth[:3, :3], truth[:3, 3] = from_rotation_vector(np.array([0.4, -1.1, 0.7])), (0.05, -0.02, 0.8)
    params = SingleCylinderParams()
    poses, owners = SingleCylinderMatcher(library.models, params).hypotheses([_moved(run, truth)])
    ours = [T for T, owner in zip(poses, owners) if library.models[owner].name == "pipe_tee"]
    assert ours and len(ours) <= params.max_poses
    turns = [np.degrees(np.arccos(np.clip((np.trace(T[:3, :3].T @ truth[:3, :3]) - 1) / 2, -1, 1))) for T in ours]
    best = ours[int(np.argmin(turns))]
    assert min(turns) <= 180 / params.roll_steps + 1e-6
    # The axis midpoint goes where the truth puts it, whichever roll.
    centre = np.asarray(run.box.center)
    assert np.linalg.norm(best[:3, :3] @ centre + best[:3, 3] - (truth[:3, :3] @ centre + truth[:3, 3])) < 1e-6
    assert symmetric_add(model.points[::10], best, truth, catalog["pipe_tee"]) < 0.1 * model.diameter


def test_cylinders_of_another_size_give_no_pose(parts):
    _, library = parts
    run = _tee_run(library)
    thin = Primitive(PrimitiveKind.CYLINDER, tuple(np.r_[run.axis_point, run.axis, 0.005]), run.inliers, run.centroid,
                     run.box)
    poses, owners = SingleCylinderMatcher(library.models).hypotheses([thin])
    assert poses.shape == (0, 4, 4) and owners.shape == (0,)
    poses, _ = SingleCylinderMatcher(library.models, SingleCylinderParams(enabled=False)).hypotheses([run])
    assert len(poses) == 0


@pytest.mark.parametrize("seed", ONE_CYLINDER_TEES)
def test_a_pipe_tee_showing_only_its_run_as_a_cylinder_is_recognised(parts, seed):
    catalog, library = parts
    names = list(np.random.default_rng(seed).choice(sorted(catalog), size=4, replace=False))
    scene = workpiece_scene(np.random.default_rng(1000 + seed), {n: catalog[n].load_mesh() for n in names}, names,
                            occluder=True)
    tee = next(inst for inst in scene.instances if inst.name == "pipe_tee")
    model = library.model("pipe_tee")

    def found(params):
        return [d for d in Recognizer(library, params=params).recognize(scene.cloud).detections
                if d.model == "pipe_tee" and symmetric_add(model.points[::10], d.T_cloud_model, tee.T_camera_model,
                                                           catalog["pipe_tee"]) < 0.1 * model.diameter]

    # The resting-pose search finds some such tees too, so it is off: the test is of the cylinder.
    no_rests = OutlineParams(enabled=False)
    assert found(RecognizeParams(outline=no_rests))
    assert not found(RecognizeParams(single_cylinder=SingleCylinderParams(enabled=False), outline=no_rests))


def test_a_tee_whose_branch_is_hidden_is_not_posed_from_its_run_alone(parts):
    # Seed 4's scene seen by a 1280x720 sensor at 910 px: the arm hides the tee's branch. Its run alone
    # gave a pose rolled 33 degrees off (0.12 d) that passed every check of the whole part; what lies
    # off the run has 5 supported points there, against 104 and 686 for the two tees found above.
    catalog, library = parts
    names = list(np.random.default_rng(4).choice(sorted(catalog), size=4, replace=False))
    hd = CameraIntrinsics(width=1280, height=720, fx=910.0, fy=910.0, cx=639.5, cy=359.5)
    scene = workpiece_scene(np.random.default_rng(1004), {n: catalog[n].load_mesh() for n in names}, names,
                            intrinsics=hd, occluder=True)
    tee = next(inst for inst in scene.instances if inst.name == "pipe_tee")
    model = library.model("pipe_tee")
    for d in Recognizer(library).recognize(scene.cloud).detections:
        if d.model == "pipe_tee":
            assert symmetric_add(model.points[::10], d.T_cloud_model, tee.T_camera_model,
                                 catalog["pipe_tee"]) < 0.1 * model.diameter


@pytest.mark.parametrize("bad, fragment", [
    (dict(roll_steps=0), "roll_steps"),
    (dict(min_length_ratio=1.2, max_length_ratio=1.1), "min_length_ratio must be <= max_length_ratio"),
    (dict(min_score=1.5), "min_score"),
    (dict(check="coarse"), "check"),
])
def test_bad_single_cylinder_params_are_refused(bad, fragment):
    with pytest.raises(InvalidInputError, match=fragment):
        SingleCylinderParams(**bad)
