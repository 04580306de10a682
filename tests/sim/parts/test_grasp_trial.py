"""Grasps tried once in MuJoCo (sim/parts/grasp_trial.py): close, lift, shake, on shapes whose outcome is known:
a box held across its faces, pads closing on air beside it, and a heavy bar held by one end or by its middle."""

import math

import pytest
import trimesh

from sim.errors import SimInputError
from sim.parts.grasp import Grasp
from sim.parts.grasp_trial import GraspTrialParams, trial_grasps, verified_grasps

DOWN = (0.0, 0.0, -1.0)


def _resting_box(extents, path):
    """A box (m) resting on z = 0 in its model frame, and its STL, which is its own convex hull."""
    box = trimesh.creation.box(extents)
    box.apply_translation((0.0, 0.0, extents[2] / 2))
    box.export(path)
    return box, [path]


def _pads_low(extents) -> float:
    """The tool height that keeps the pads' lower ends (17.5 mm below it) 1.5 mm off the table, as the planner
    does, or the box's half height if that is higher."""
    return max(0.019, extents[2] / 2)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    return _resting_box((0.05, 0.03, 0.04), tmp_path_factory.mktemp("box") / "box.stl")


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    """A 250 x 20 x 20 mm bar."""
    return _resting_box((0.25, 0.02, 0.02), tmp_path_factory.mktemp("bar") / "bar.stl")


def test_a_box_gripped_across_its_faces_is_held_through_lift_and_shake(box):
    mesh, hulls = box
    across = Grasp("across", (0, 0, 0.02), DOWN, (0, 1, 0), 0.03)
    along = Grasp("along", (0, 0, 0.02), DOWN, (1, 0, 0), 0.05)
    for trial in trial_grasps(mesh, hulls, 0.2, [across, along]):
        assert trial.held, trial.why
        assert trial.why == ""
        assert 0 <= trial.slip_mm < 1.0 and 0 <= trial.slip_deg < 1.0


def test_pads_closing_on_air_beside_the_part_fail_with_the_reason(box):
    mesh, hulls = box
    beside = Grasp("beside", (0.06, 0, 0.02), DOWN, (0, 1, 0), 0.03)
    (trial,) = trial_grasps(mesh, hulls, 0.2, [beside])
    assert not trial.held
    assert trial.why == "closed on air"
    assert trial.slip_mm is None and trial.slip_deg is None


def test_a_heavy_bar_gripped_at_one_end_turns_out_of_the_hand_but_not_by_its_middle(bar):
    mesh, hulls = bar
    z = _pads_low((0.25, 0.02, 0.02))
    end, middle = Grasp("end", (0.11, 0, z), DOWN, (0, 1, 0), 0.02), Grasp("middle", (0, 0, z), DOWN, (0, 1, 0), 0.02)
    at_end, at_middle = trial_grasps(mesh, hulls, 1.0, [end, middle])  # 1 kg: 1 N m about the pads at the end
    assert not at_end.held
    assert "while lifting" in at_end.why and ("slip" in at_end.why or "dropped" in at_end.why)
    params = GraspTrialParams()
    assert at_end.slip_mm > params.slip_mm or at_end.slip_deg > params.slip_deg or "dropped" in at_end.why
    assert at_middle.held, at_middle.why
    assert at_middle.slip_mm < 1.0 and at_middle.slip_deg < 1.0


def test_the_same_trials_give_the_same_numbers(bar):
    mesh, hulls = bar
    z = _pads_low((0.25, 0.02, 0.02))
    grasps = [Grasp("end", (0.11, 0, z), DOWN, (0, 1, 0), 0.02), Grasp("middle", (0.02, 0, z), DOWN, (0, 1, 0), 0.02)]
    first = trial_grasps(mesh, hulls, 1.0, grasps)
    assert trial_grasps(mesh, hulls, 1.0, grasps) == first
    assert trial_grasps(mesh, hulls, 1.0, grasps[1:]) == first[1:]  # each trial starts from the same state


def test_verified_grasps_keep_those_that_hold_then_the_untried(box):
    mesh, hulls = box
    beside = Grasp("beside", (0.06, 0, 0.02), DOWN, (0, 1, 0), 0.03)
    across = Grasp("across", (0, 0, 0.02), DOWN, (0, 1, 0), 0.03)
    along = Grasp("along", (0, 0, 0.02), DOWN, (1, 0, 0), 0.05)
    verified = verified_grasps(mesh, hulls, 0.2, [beside, across, along], params=GraspTrialParams(trials_per_rest=2))
    assert [g.name for g in verified.grasps] == ["across", "along"]  # "along" was not tried
    assert [(t.grasp, t.held) for t in verified.trials] == [("beside", False), ("across", True)]


def test_when_the_best_fail_the_next_are_tried_up_to_the_cap(box):
    mesh, hulls = box
    air = [Grasp(f"beside_{k}", (0.06 + 0.01 * k, 0, 0.02), DOWN, (0, 1, 0), 0.03) for k in range(3)]
    across = Grasp("across", (0, 0, 0.02), DOWN, (0, 1, 0), 0.03)
    found = verified_grasps(mesh, hulls, 0.2, [*air, across], params=GraspTrialParams(trials_per_rest=1))
    assert [g.name for g in found.grasps] == ["across"] and len(found.trials) == 4
    capped = GraspTrialParams(trials_per_rest=1, max_trials_per_rest=2)
    none = verified_grasps(mesh, hulls, 0.2, [*air, across], params=capped)
    assert none.grasps == () and [t.grasp for t in none.trials] == ["beside_0", "beside_1"]


def test_a_grasp_not_from_above_in_the_rest_is_not_tried(box):
    mesh, hulls = box
    on_its_side = trimesh.transformations.rotation_matrix(math.pi / 2, (1, 0, 0))  # model +z now along -y
    sideways = Grasp("sideways", (0, 0, 0.02), DOWN, (1, 0, 0), 0.05)
    (trial,) = trial_grasps(mesh, hulls, 0.2, [sideways], on_its_side)
    assert not trial.held and "not approached from above" in trial.why


@pytest.mark.parametrize("field, value, fragment", [
    ("lift", -0.1, "lift"), ("shake_frequency", 0, "shake_frequency"), ("slip_mm", math.nan, "slip_mm"),
    ("shake_cycles", 2.0, "shake_cycles"), ("trials_per_rest", 0, "trials_per_rest"),
    ("max_trials_per_rest", 2, "max_trials_per_rest"), ("settle_s", -1, "settle_s"),
])
def test_bad_params_are_refused_naming_the_field(field, value, fragment):
    with pytest.raises(SimInputError, match=fragment):
        GraspTrialParams(**{field: value})


def test_bad_inputs_are_refused_with_the_fix(box, tmp_path):
    mesh, hulls = box
    grasp = [Grasp("across", (0, 0, 0.02), DOWN, (0, 1, 0), 0.03)]
    with pytest.raises(SimInputError, match=r"missing \(.*gone\.stl\).*collision_hulls"):
        trial_grasps(mesh, [tmp_path / "gone.stl"], 0.2, grasp)
    with pytest.raises(SimInputError, match="mass must be a positive number of kg"):
        trial_grasps(mesh, hulls, 0.0, grasp)
