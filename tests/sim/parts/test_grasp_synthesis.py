"""Parallel-jaw grasps synthesised from a mesh alone (sim/parts/grasp_synthesis.py), on shapes whose grasps
are known: boxes, cylinders standing and lying, a block on a plate, and parts the gripper cannot take."""

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import trimesh

from sim.errors import SimInputError
from sim.parts.grasp_synthesis import GraspSynthesisParams, synthesise_grasps
from sim.world.assets import ARM_XML

PARAMS = GraspSynthesisParams()


def _resting(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    mesh.apply_translation((0.0, 0.0, -mesh.bounds[0, 2]))
    return mesh


def _box(extents) -> trimesh.Trimesh:
    return _resting(trimesh.creation.box(extents))


def _synthesised(mesh, seed=0, **params):
    return synthesise_grasps(mesh, np.random.default_rng(seed), GraspSynthesisParams(**params))


@pytest.fixture(scope="module")
def box_grasps():
    return _synthesised(_box((0.05, 0.03, 0.04)))


def test_a_box_is_grasped_across_its_faces_from_above(box_grasps):
    assert 0 < len(box_grasps) <= PARAMS.max_grasps
    assert [g.name for g in box_grasps] == [f"synth_{k}" for k in range(len(box_grasps))]
    axes = set()
    for g in box_grasps:
        np.testing.assert_allclose(g.approach, (0, 0, -1))
        assert g.closing[2] == 0 and abs(np.linalg.norm(g.closing) - 1) < 1e-9
        axis = int(np.argmax(np.abs(g.closing[:2])))
        assert abs(g.closing[axis]) > math.cos(math.radians(3)), g.closing  # along x or y within 3 degrees
        assert abs(g.width - (0.05, 0.03)[axis]) < 1e-3
        assert abs(g.point[1 - axis]) < 0.015 + 1e-9  # the pads on the face, the grasp midway between them
        axes.add(axis)
    assert axes == {0, 1}  # both spans fit the 80 mm gripper, and both are offered


def test_the_pads_stay_above_the_table(box_grasps):
    for g in box_grasps:
        assert g.point[2] - PARAMS.pad_half_size[2] >= PARAMS.table_clearance - 1e-12


def test_the_same_seed_gives_the_same_grasps_bit_for_bit(box_grasps):
    again = _synthesised(_box((0.05, 0.03, 0.04)))
    assert len(again) == len(box_grasps)
    for a, b in zip(again, box_grasps):
        assert a.name == b.name and a.width == b.width
        assert np.array_equal(a.point, b.point) and np.array_equal(a.closing, b.closing)


def test_a_standing_cylinder_is_grasped_across_its_axis():
    cylinder = _resting(trimesh.creation.cylinder(radius=0.02, height=0.05, sections=64))
    grasps = _synthesised(cylinder)
    assert len(grasps) >= 2
    for g in grasps:
        assert abs(g.width - 0.04) < 1e-3
        assert np.hypot(*g.point[:2]) < 0.002


def test_a_lying_cylinder_is_grasped_across_its_diameter():
    rod = trimesh.creation.cylinder(radius=0.015, height=0.1, sections=64)  # 100 mm long: no grasp end to end
    rod.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, (0, 1, 0)))  # axis along x
    grasps = _synthesised(_resting(rod))
    assert grasps
    for g in grasps:
        assert abs(g.closing[0]) < math.sin(math.radians(3)) and g.closing[2] == 0
        assert abs(g.width - 0.03) < 1e-3
        assert abs(g.point[1]) < 0.002


def test_a_block_on_a_thin_plate_is_grasped_with_the_pads_above_the_plate():
    plate = _box((0.12, 0.1, 0.002))  # wider than the gripper opens
    block = trimesh.creation.box((0.02, 0.03, 0.02))
    block.apply_translation((0.0, 0.0, 0.002 + 0.01))
    grasps = _synthesised(trimesh.util.concatenate([plate, block]))
    assert grasps
    for g in grasps:
        assert abs(g.width - (0.02 if abs(g.closing[0]) > 0.99 else 0.03)) < 1e-3
        assert g.point[2] - PARAMS.pad_half_size[2] >= 0.002 + PARAMS.clearance - 1e-6  # clear of the plate


def test_a_part_too_wide_from_every_side_is_refused_naming_the_opening():
    with pytest.raises(SimInputError, match=r"too wide for the gripper from every side: narrowest span 100 mm, "
                                            r"the gripper opens 80 mm"):
        _synthesised(_box((0.12, 0.1, 0.03)))


def test_a_part_in_millimetres_is_refused_with_a_hint():
    with pytest.raises(SimInputError, match="millimetres"):
        _synthesised(_box((50.0, 30.0, 40.0)), max_samples=2000, seeds=200)


def test_a_part_whose_sides_fit_only_where_the_fingers_would_hit_is_refused():
    # A 20 mm post inside a square ring 80 mm across with 7 mm walls: the ring is too wide, its walls too thin
    # to pinch, and whatever spans the post leaves the fingers coming down onto the ring.
    parts = [_box((0.02, 0.02, 0.04))]
    for side in (-1, 1):
        parts += [_box((0.007, 0.08, 0.04)), _box((0.066, 0.007, 0.04))]
        parts[-2].apply_translation((side * 0.0365, 0.0, 0.0))
        parts[-1].apply_translation((0.0, side * 0.0365, 0.0))
    with pytest.raises(SimInputError, match="the fingers or the palm would hit it"):
        _synthesised(trimesh.util.concatenate(parts), seeds=300)  # fewer seeds: a faster test, the same verdict


def test_a_part_without_steep_sides_is_refused():
    with pytest.raises(SimInputError, match="no side of it is within 28 deg of vertical"):
        _synthesised(trimesh.creation.cone(radius=0.03, height=0.02, sections=64))


def test_a_mesh_off_the_table_is_refused():
    box = trimesh.creation.box((0.05, 0.03, 0.04))  # centred on the origin: half of it under the table
    with pytest.raises(SimInputError, match="must rest on the table plane z = 0"):
        _synthesised(box)


@pytest.mark.parametrize("field, value", [("pad_half_size", (0.004, 0.01)), ("cone_share", 0.0),
                                          ("min_width", 0.09), ("seeds", 2.5), ("clearance", float("nan"))])
def test_bad_params_are_refused(field, value):
    with pytest.raises(SimInputError, match=field):
        GraspSynthesisParams(**{field: value})


def _geom(root, name):
    return next(g for g in root.iter("geom") if g.get("name") == name)


def _floats(element, attribute):
    return tuple(float(v) for v in element.get(attribute).split())


def test_the_defaults_are_the_arms_gripper():
    root = ET.parse(ARM_XML).getroot()
    bodies = {b.get("name"): b for b in root.iter("body")}
    tool_z = _floats(next(s for s in root.iter("site") if s.get("name") == "tool"), "pos")[2]
    finger_z = _floats(bodies["left_finger"], "pos")[2]
    pad, finger, palm = _geom(root, "left_pad"), _geom(root, "left_finger_collision"), _geom(root, "gripper_collision")
    pad_class = next(d for d in root.iter("default") if d.get("class") == "pad").find("geom")
    gripper = next(a for a in root.iter("position") if a.get("name") == "gripper")
    finger_joint = next(d for d in root.iter("default") if d.get("class") == "finger").find("joint")

    assert _floats(pad, "size") == PARAMS.pad_half_size
    assert math.isclose(_floats(pad, "pos")[0], PARAMS.pad_half_size[0])  # the face at the joint's value
    assert math.isclose(finger_z + _floats(pad, "pos")[2], tool_z)  # the pads' centres level with the tool
    assert _floats(finger, "size") == PARAMS.finger_half_size
    np.testing.assert_allclose((_floats(finger, "pos")[0], tool_z - finger_z - _floats(finger, "pos")[2]),
                               PARAMS.finger_offset)
    assert _floats(palm, "size") == PARAMS.palm_half_size
    assert math.isclose(tool_z - _floats(palm, "pos")[2], PARAMS.palm_height)
    assert _floats(pad_class, "friction")[0] == PARAMS.friction
    assert _floats(gripper, "ctrlrange")[1] == PARAMS.max_opening == 2 * _floats(finger_joint, "range")[1]


def test_the_defaults_are_the_planners():
    from sim.skills.grasp_planning import PAD_CLEARANCE
    from sim.world.robot import ArmConfig

    assert PARAMS.table_clearance == PAD_CLEARANCE
    assert PARAMS.max_opening == ArmConfig().max_opening
