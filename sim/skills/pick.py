"""Executing one pick-and-place and judging it on the simulator's truth.

:func:`pick_and_place` plans a grasp from a pose estimate of one part (:mod:`sim.skills.grasp_planning`)
and executes it by ramping the arm's position targets while stepping the simulation: pre-grasp,
approach, close, lift, transport above the fixture, descend, open, retreat. Every success check
reads the simulator's truth (contacts and body poses), never the plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from psorr.synthetic.catalog import symmetry_transforms
from sim.control.cell import ArmCell
from sim.control.ik import T_world_site
from sim.errors import SimInputError, UnreachableTargetError, WorkspaceBlockedError
from sim.skills.grasp_planning import (
    LIFT,
    PRE_GRASP,
    WALL_CLEARANCE,
    angle_deg,
    plan_grasp,
    replan_place,
    shift,
    upright_equivalent,
)
from sim.skills.in_hand import InHandLook, look_in_hand
from sim.world import World

MIN_LIFT = 0.05  # m the part must rise to count as grasped
PLACE_TOL_MM = 5.0
PLACE_TOL_DEG = 3.0
REST_TOL_MM = 3.0  # the seated part's origin (its resting face) within this of the table top
REST_TOL = 0.02  # m: estimates further from the table top than this are not resting on it
REST_TILT_DEG = 20.0  # estimates tilted more than this are not resting on the table


@dataclass(frozen=True)
class PickResult:
    """Outcome of one pick-and-place (metres, degrees).

    Attributes:
        part: the workpiece.
        grasp_name: the catalog grasp used ("" when none was executed).
        grasped: both pads touched the part, it rose >= MIN_LIFT and was still held after transport.
        lifted_m: how far the part's origin rose above its start height after the lift (truth).
        placed: after release and a settle the part sits in its fixture (within 5 mm and 3 deg of
            yaw, modulo its symmetries) and rests on the table.
        place_error_mm, place_error_deg: the final true pose against the fixture pose (nan if never placed).
        pose_error_mm, rot_error_deg: the pose estimate the pick was planned from against the true start
            pose (0 for the oracle), before any look in the hand.
        note: what happened, for the log.
        looks: how many times the robot looked at the cell before committing to this pick.
        in_hand: the look at the held part that told its near-symmetric twins apart (None if the
            estimate had no twin left to rule out, or there was nobody to look).
    """

    part: str
    grasp_name: str
    grasped: bool
    lifted_m: float
    placed: bool
    place_error_mm: float
    place_error_deg: float
    pose_error_mm: float
    rot_error_deg: float
    note: str
    looks: int = 1
    in_hand: InHandLook | None = None


def pose_error(T_est: np.ndarray, T_true: np.ndarray, info) -> tuple[float, float]:
    """(mm, deg): position and rotation error of ``T_est`` against ``T_true``, least over the symmetries."""
    best = (math.inf, math.inf)
    for S in symmetry_transforms(info):
        T = T_true @ S
        e = (float(np.linalg.norm(T_est[:3, 3] - T[:3, 3])) * 1e3, angle_deg(T_est[:3, :3].T @ T[:3, :3]))
        if e[0] + e[1] < best[0] + best[1]:
            best = e
    return best


def fixture_error(T_true: np.ndarray, T_fixture: np.ndarray, info) -> tuple[float, float, float]:
    """(xy mm, yaw deg, tilt deg) of a part's true pose against its fixture pose, least over symmetries."""
    best = (math.inf, math.inf, math.inf)
    for S in symmetry_transforms(info):
        T = T_fixture @ S
        R = T[:3, :3].T @ T_true[:3, :3]
        yaw = abs(math.degrees(math.atan2(R[1, 0], R[0, 0])))
        tilt = math.degrees(math.acos(float(np.clip(R[2, 2], -1.0, 1.0))))
        pos = float(np.linalg.norm(T_true[:3, 3] - T[:3, 3])) * 1e3
        if pos + yaw + tilt < sum(best):
            best = (pos, yaw, tilt)
    return best


def resting_on_table(world: World, T_world_part: np.ndarray, part: str) -> bool:
    """Whether a pose of ``part`` could be resting on the table: one of its symmetric equivalents has
    its origin (on its resting face) within ``REST_TOL`` of the table top and tilts at most
    ``REST_TILT_DEG``, and its origin is over the table."""
    hx, hy = (v / 2 for v in world.config.table_size)
    if abs(T_world_part[0, 3]) > hx or abs(T_world_part[1, 3]) > hy:
        return False
    T = upright_equivalent(np.asarray(T_world_part, dtype=float), world.catalog[part])
    return abs(T[2, 3] - world.table_top) <= REST_TOL and T[2, 2] >= math.cos(math.radians(REST_TILT_DEG))


def pick_and_place(world: World, part: str, T_world_part_estimate: np.ndarray,
                   cell: ArmCell | None = None, alternatives: tuple[np.ndarray, ...] = (),
                   perception=None) -> PickResult:
    """Pick ``part`` using the pose estimate and seat it in its fixture; checks read the simulator.

    ``world.data`` is stepped in place (the arm ends retreated above the fixture) through ``cell``
    (default: a new :class:`ArmCell` with no human, monitor or recorder). The execution is
    deterministic. A protective stop that lasts too long ends the pick unfinished.

    ``alternatives`` are the estimate's near-symmetric twins (4, 4, world) that the look could not
    rule out. Given them and a recognising ``perception`` (:class:`sim.skills.perception.Perception`), the
    robot turns the part in its hand after the lift and looks again (:mod:`sim.skills.in_hand`), and seats
    it the way round that look finds.
    """
    if part not in world.workpieces:
        raise SimInputError(f"unknown part {part!r}; the world has {list(world.workpieces)}")
    if part not in world.T_world_fixtures:
        raise SimInputError(f"{part} has no fixture: build the world with fixtures=True")
    cell = ArmCell(world) if cell is None else cell
    info = world.catalog[part]
    T_est = upright_equivalent(np.asarray(T_world_part_estimate, float), info)
    twins = [upright_equivalent(np.asarray(T, float), info) for T in alternatives] if perception is not None else []
    body = world.model.body(part).id
    mujoco.mj_forward(world.model, world.data)
    T_start = world.body_pose(part)
    pos_mm, rot_deg = pose_error(T_est, T_start, info)

    seen_in_hand = None

    def result(grasp="", grasped=False, lifted=0.0, placed=False, pe=math.nan, pd=math.nan, note=""):
        return PickResult(part, grasp, grasped, float(lifted), placed, float(pe), float(pd), pos_mm, rot_deg, note,
                          in_hand=seen_in_hand)

    if not resting_on_table(world, T_est, part):
        return result(note=f"estimate not resting upright on the table (z {T_est[2, 3] - world.table_top:+.3f} m "
                           f"above it, tilted {math.degrees(math.acos(np.clip(T_est[2, 2], -1, 1))):.0f} deg): "
                           "no pick planned")
    plan, why = plan_grasp(cell, part, T_est)
    if plan is None:
        return result(note=f"no reachable grasp: {why}")
    g = plan.grasp
    approach_w = plan.T_grasp[:3, 2]

    def give_up(lifted: float, why: str) -> PickResult:
        """Open, back the tool off straight up (so the next move sweeps nothing), report."""
        cell.holding = None
        try:
            cell.gripper_to(world.arm.gripper_open, 0.4)
            q = cell.commanded_q()
            T = T_world_site(world.model, world.kinematics(q), world.arm.tool_site)
            cell.follow(cell.path(q, T, shift(T, [0, 0, LIFT])), 0.8)
        except (UnreachableTargetError, WorkspaceBlockedError):
            pass
        cell.keep_awake(None)
        return result(g.name, False, lifted, note=why)

    def execute() -> PickResult:
        nonlocal seen_in_hand
        cell.gripper_to(world.arm.gripper_open, 0.2)
        # Pre-grasp in joint space, then a straight approach.
        cell.move_joints(plan.q_pre[cell.qadr], ramp_s=1.5)
        T_pre = shift(plan.T_grasp, -PRE_GRASP * approach_w)
        cell.follow(cell.path(plan.q_pre, T_pre, plan.T_grasp), 1.0)
        cell.gripper_to(min(world.arm.gripper_open, g.width + 0.006), 0.1, ramp_s=0.3)
        cell.gripper_to(world.arm.gripper_closed, 0.4, ramp_s=0.6)  # squeeze gently: a snap shoves the part
        touching = cell.pads_touch(body)
        cell.holding = part
        # Awake until the gripper has let go and backed off: asleep against a pad, it would stay there.
        cell.keep_awake(part)
        if cell.recorder is not None:
            cell.recorder.grasped(world, world.data, part)
        # Lift straight up.
        T_lift = shift(plan.T_grasp, [0, 0, LIFT])
        qs = cell.path(plan.q_grasp, plan.T_grasp, T_lift)
        cell.follow(qs, 1.0)
        lifted = float(world.body_pose(part)[2, 3] - T_start[2, 3])
        held = cell.pads_touch(body)
        if not (held and lifted >= MIN_LIFT):
            return give_up(lifted, f"grasp failed: both pads on the part at closing {touching}, "
                                   f"after the lift {held}; lifted {lifted * 100:.1f} cm")
        grip = "" if touching else "both pads touched only after the lift began; "
        T_place, q_place_above, pads_clear = plan.T_place, plan.q_place_above, plan.pads_clear_fixture
        if twins:
            T_tool_parts = [np.linalg.inv(plan.T_grasp) @ T for T in [T_est, *twins]]
            seen_in_hand = look_in_hand(cell, perception, part, qs[-1], T_lift, T_tool_parts)
            grip += seen_in_hand.summary() + "; "
            if seen_in_hand.chosen:
                T_part_tool = np.linalg.inv(T_tool_parts[seen_in_hand.chosen])
                replanned = replan_place(cell, part, g, T_part_tool, qs[-1], plan.T_grasp)
                if replanned is None:  # seated as first planned, rather than dropped from the lift height
                    grip += "held the other way round, but no seat for it that way is reachable; "
                else:
                    T_place, q_place_above, pads_clear = replanned
        # Transport at the lift height along an arc about the base, then descend.
        T_above = shift(T_place, [0, 0, T_lift[2, 3] - T_place[2, 3]])
        try:
            qs = cell.path(qs[-1], T_lift, T_above, arc=True)
        except UnreachableTargetError:  # no continuous arc: one joint-space move to the planned configuration
            qs = [q_place_above]
        cell.follow(qs, 2.5)
        if not (cell.pads_touch(body) and world.body_pose(part)[2, 3] - T_start[2, 3] >= MIN_LIFT):
            return give_up(lifted, "dropped during transport")
        # Release just above seating, or higher when the pads would otherwise land on the fixture's walls
        # (they stick out past the part along the closing direction, further than the pocket's clearance).
        wall_top = world.table_top + world.config.fixture_wall[1] + WALL_CLEARANCE
        drop = 0.002 if pads_clear else max(0.002, wall_top - (T_place[2, 3] - cell.pad_reach))
        T_release = shift(T_place, [0, 0, drop])
        qs = cell.path(qs[-1], T_above, T_release)
        cell.follow(qs, 1.2)
        cell.gripper_to(min(world.arm.gripper_open, g.width + 0.012), 0.3, ramp_s=0.3)  # ease off, no fling
        cell.holding = None
        cell.follow(cell.path(qs[-1], T_release, T_above), 0.8)
        cell.gripper_to(world.arm.gripper_open, 0.3)  # the part has settled ~1.4 s since release
        cell.keep_awake(None)
        T_final = world.body_pose(part)
        pe, yaw, tilt = fixture_error(T_final, world.T_world_fixtures[part], info)
        xy = float(np.linalg.norm(T_final[:2, 3] - world.T_world_fixtures[part][:2, 3])) * 1e3
        rests = abs(T_final[2, 3] - world.table_top) * 1e3 <= REST_TOL_MM and tilt <= PLACE_TOL_DEG
        placed = bool(pe <= PLACE_TOL_MM and yaw <= PLACE_TOL_DEG and rests)  # not numpy.bool_: JSON wrote 0.0
        note = (f"placed: {pe:.1f} mm (xy {xy:.1f}), yaw {yaw:.1f} deg, tilt {tilt:.1f} deg, "
                f"z {1e3 * (T_final[2, 3] - world.table_top):+.1f} mm over the table")
        return result(g.name, True, lifted, placed, pe, yaw, grip + (note if placed else "not seated: " + note[8:]))



    try:
        return execute()
    except (UnreachableTargetError, WorkspaceBlockedError) as exc:
        return give_up(float(world.body_pose(part)[2, 3] - T_start[2, 3]), f"aborted mid-pick: {exc}")
