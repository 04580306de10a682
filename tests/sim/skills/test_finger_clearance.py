"""The fingers' extent and the fixture's pocket (sim/skills/finger_clearance.py). Headless."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from sim.control.cell import ArmCell
from sim.skills.finger_clearance import (
    PRESHAPE,
    RELEASE_EASE,
    finger_corners,
    finger_reach,
    fingers_clear_fixture,
    fingers_on_furniture,
)
from sim.world import WorldConfig, build_world

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def cell():
    return ArmCell(build_world(WorldConfig(workpieces=("chassis",)), np.random.default_rng(0)))


def test_the_fingers_stand_behind_the_pads_and_reach_as_low(cell):
    corners = finger_corners(cell, 0.04)
    x = np.abs(corners[:, 0])
    assert x.min() == pytest.approx(0.02)  # the pads' faces, 40 mm apart
    pad_thickness = 2 * cell.model.geom_size[cell.pads[0]][0]
    assert x.max() > 0.02 + pad_thickness + 0.005  # the fingers' backs, well past the pads
    assert finger_reach(cell, 0.04) == pytest.approx(cell.pad_reach)
    wider = finger_corners(cell, 0.06)
    assert np.abs(wider[:, 0]).max() == pytest.approx(x.max() + 0.01)


def _fits(cell, half_extent: float, width: float, height: float = 0.0) -> bool:
    """Tool straight down over the middle of a square part ``2 half_extent`` wide, closing along x."""
    box = np.array([[-half_extent, -half_extent, 0.0], [half_extent, half_extent, 0.02]])
    info = SimpleNamespace(bounds=lambda: box)
    T_fix_tool = np.diag([1.0, -1.0, -1.0, 1.0])  # approach (z) down
    T_fix_tool[2, 3] = cell.pad_reach + height  # the pads' lower ends at ``height`` over the table
    return fingers_clear_fixture(cell, info, T_fix_tool, width)


def test_fingers_must_fit_the_pocket_closed_and_eased_open(cell):
    clearance = cell.world.config.fixture_clearance
    back = float(np.abs(finger_corners(cell, 0.0)[:, 0]).max())  # a finger's back from its pad's face
    # A post in the middle of a wide plate: the fingers stay well inside the pocket.
    assert _fits(cell, 0.08, 0.02)
    # Closed, the fingers' backs are 1 mm inside the pocket's wall; eased open, they would be past it.
    half = 0.05
    width = 2 * (half + clearance - back - 0.001)
    assert width + RELEASE_EASE < 2 * half
    assert not _fits(cell, half, width)
    # Above the walls, nothing is in their way.
    assert _fits(cell, half, width, height=cell.world.config.fixture_wall[1] + 0.005)


def test_the_chassis_is_seated_where_its_fingers_once_landed_on_the_fixtures_walls():
    """Kit seed [6, 0]: closed across its walls, the fingers behind the pads came down on the fixture's walls
    and were pinned there as they opened; the chassis was left propped 8 degrees on a wall."""
    from sim.skills.pick import pick_and_place
    from sim.world.tasks import load_task

    world = build_world(load_task(REPO / "tasks" / "kit.yaml").world, np.random.default_rng([6, 0]))
    result = pick_and_place(world, "chassis", world.T_world_workpieces["chassis"])
    assert result.placed and result.place_error_mm < 1.0, result.note


def test_fingers_that_would_land_on_a_fixture_beside_the_part_approach_opened_only_past_its_width():
    """Demo seed [0, 32]: the U-channel lies beside the flanged hub's fixture. Opened wide (80 mm) on the way
    down, every grasp's fingers land on that fixture's walls, the arm stops 8 mm short and the pads close
    off centre; opened just past the grasp's width, they clear it and the part is seated."""
    from sim.skills.grasp_planning import plan_grasp
    from sim.skills.pick import pick_and_place
    from sim.world.tasks import load_task

    world = build_world(load_task(REPO / "tasks" / "demo.yaml").world, np.random.default_rng([0, 32]))
    cell = ArmCell(world)
    plan = plan_grasp(cell, "u_channel", world.T_world_workpieces["u_channel"])
    assert plan.approach_opening == pytest.approx(plan.grasp.width + PRESHAPE)
    assert "flanged_hub_fixture" in fingers_on_furniture(cell, plan.q_grasp, world.arm.gripper_open)
    assert fingers_on_furniture(cell, plan.q_grasp, plan.approach_opening) == ""
    result = pick_and_place(world, "u_channel", world.T_world_workpieces["u_channel"], cell)
    assert result.placed and result.place_error_mm < 1.0, result.note
