"""Executing one pick-and-place, step by step, and judging it on the simulator's truth.

:func:`pick_and_place` reads as the steps it runs. It checks that the estimate rests on the table and
plans a grasp from it (:mod:`sim.skills.grasp_planning`); then the arm :func:`approach` es the part,
:func:`close_on_part`, :func:`lift` s it, :func:`choose_seat` (for a part with a near-symmetric twin,
after a look in the hand, :mod:`sim.skills.in_hand`), :func:`transport` s it above the fixture,
:func:`release` s it there and :func:`retreat` s, and :func:`judge` reads the outcome. A step that cannot
go on ends the pick in :func:`give_up`. Each step ramps the arm's position targets while stepping the
simulation and hands the next a frozen record of where it left the arm and the part; every success
check reads the simulator's truth (contacts and body poses, :mod:`sim.skills.judging`), never the plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from sim.control.cell import ArmCell
from sim.control.ik import T_world_site
from sim.errors import SimInputError, UnreachableTargetError, WorkspaceBlockedError
from sim.skills.finger_clearance import PRESHAPE, RELEASE_EASE, WALL_CLEARANCE, finger_reach
from sim.skills.grasp_planning import (
    LIFT,
    PRE_GRASP,
    GraspPlan,
    NoGrasp,
    PlacePlan,
    plan_grasp,
    replan_place,
    shift,
    upright_equivalent,
)
from sim.skills.in_hand import InHandLook, look_in_hand
from sim.skills.judging import MIN_LIFT, PickResult, not_resting_note, placement, pose_error, resting_on_table
from sim.world import World


@dataclass(frozen=True, eq=False)
class PickStart:
    """What a pick starts from. Poses are (4, 4) in the world frame.

    Attributes:
        world, cell: the cell, stepped in place through ``cell``.
        part: the workpiece; body: its body id.
        T_est: the estimate, re-expressed by the symmetry that stands upright (the pose planned on).
        twins: the estimate's near-symmetric twins, upright, to tell apart in the hand (empty without
            a ``perception`` to look with).
        perception: the robot's :class:`sim.skills.perception.Perception`, or None.
        T_start: the part's true pose before the pick.
        pose_error_mm, rot_error_deg: ``T_est`` against ``T_start``, least over the part's symmetries.
    """

    world: World
    cell: ArmCell
    part: str
    body: int
    T_est: np.ndarray
    twins: tuple[np.ndarray, ...]
    perception: object | None
    T_start: np.ndarray
    pose_error_mm: float
    rot_error_deg: float

    def risen(self) -> float:
        """How far (m) the part's origin is above where it started, now (truth)."""
        return float(self.world.body_pose(self.part)[2, 3] - self.T_start[2, 3])

    def result(self, grasp="", grasped=False, lifted=0.0, placed=False, error_mm=math.nan, error_deg=math.nan,
               note="", in_hand: InHandLook | None = None) -> PickResult:
        """The pick's :class:`PickResult`, with this start's estimate errors."""
        return PickResult(self.part, grasp, grasped, float(lifted), placed, float(error_mm), float(error_deg),
                          self.pose_error_mm, self.rot_error_deg, note, in_hand=in_hand)


@dataclass(frozen=True, eq=False)
class Lifted:
    """The gripper closed and rose: the tool pose (4, 4, world) and joints (nq,) at the lift height, how far
    the part rose (m, truth), and whether both pads touched it when closing and after the lift."""

    T_tool: np.ndarray
    q: np.ndarray
    height: float
    touching_at_close: bool
    touching_after_lift: bool

    @property
    def held(self) -> bool:
        """Both pads on the part after the lift, and it rose at least MIN_LIFT."""
        return bool(self.touching_after_lift and self.height >= MIN_LIFT)

    def failure(self) -> str:
        return (f"grasp failed: both pads on the part at closing {self.touching_at_close}, after the lift "
                f"{self.touching_after_lift}; lifted {self.height * 100:.1f} cm")


@dataclass(frozen=True, eq=False)
class Seat:
    """Where the held part goes (``place``), the look in the hand that decided it (None without one),
    and what the grip and the look said, for the pick's note."""

    place: PlacePlan
    in_hand: InHandLook | None
    note: str


@dataclass(frozen=True, eq=False)
class Carried:
    """The part carried above its seat: the tool pose (4, 4, world) and joints (nq,) there, and whether
    both pads still hold it at least MIN_LIFT above where it started (truth)."""

    T_above: np.ndarray
    q: np.ndarray
    held: bool


@dataclass(frozen=True, eq=False)
class Released:
    """The gripper eased open at ``T_release``, with joints ``q`` (nq,), under ``T_above`` (4, 4, world)."""

    T_release: np.ndarray
    T_above: np.ndarray
    q: np.ndarray


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
    start = start_pick(world, part, T_world_part_estimate, cell, alternatives, perception)
    if not resting_on_table(world, start.T_est, part):
        return start.result(note=not_resting_note(world, start.T_est))
    plan = plan_grasp(start.cell, part, start.T_est)
    if isinstance(plan, NoGrasp):
        return start.result(note=f"no reachable grasp: {plan.why}")
    if start.cell.recorder is not None:
        start.cell.recorder.planned(world, world.data, part, plan)
    seat = None
    try:
        approach(start, plan)
        lifted = lift(start, plan, close_on_part(start, plan))
        if not lifted.held:
            return give_up(start, plan, lifted.height, lifted.failure())
        seat = choose_seat(start, plan, lifted)
        carried = transport(start, lifted, seat)
        if not carried.held:
            return give_up(start, plan, lifted.height, "dropped during transport", seat.in_hand)
        retreat(start, release(start, plan, seat, carried))
        return judge(start, plan, lifted, seat)
    except (UnreachableTargetError, WorkspaceBlockedError) as exc:
        in_hand = seat.in_hand if seat is not None else None
        return give_up(start, plan, start.risen(), f"aborted mid-pick: {exc}", in_hand)


def start_pick(world: World, part: str, T_world_part_estimate, cell: ArmCell | None, alternatives,
               perception) -> PickStart:
    """Check the request, and read the part's true pose and the estimate's error before anything moves."""
    if part not in world.workpieces:
        raise SimInputError(f"unknown part {part!r}; the world has {list(world.workpieces)}")
    if part not in world.T_world_fixtures and world.places.get(part) != "tote":
        raise SimInputError(f"{part} has no place to go: build the world with fixtures=True")
    cell = ArmCell(world) if cell is None else cell
    info = world.catalog[part]
    T_est = upright_equivalent(np.asarray(T_world_part_estimate, float), info)
    # Which way round a part lies in the tote does not matter, so only a part for a fixture is looked at in the hand.
    twins = tuple(upright_equivalent(np.asarray(T, float), info) for T in alternatives) \
        if perception is not None and part in world.T_world_fixtures else ()
    body = world.model.body(part).id
    mujoco.mj_forward(world.model, world.data)
    T_start = world.body_pose(part)
    error_mm, error_deg = pose_error(T_est, T_start, info)
    return PickStart(world, cell, part, body, T_est, twins, perception, T_start, error_mm, error_deg)


def approach(start: PickStart, plan: GraspPlan) -> None:
    """Open the gripper, swing to the pre-grasp in joint space, then move straight in along the approach."""
    cell = start.cell
    cell.gripper_to(plan.approach_opening, 0.2)
    cell.move_joints(plan.q_pre[cell.qadr], ramp_s=1.5)
    T_pre = shift(plan.T_grasp, -PRE_GRASP * plan.T_grasp[:3, 2])
    cell.follow(cell.path(plan.q_pre, T_pre, plan.T_grasp), 1.0)


def close_on_part(start: PickStart, plan: GraspPlan) -> bool:
    """Close the gripper on the part; whether both pads touch it. From here the cell holds the part."""
    cell, world, part = start.cell, start.world, start.part
    cell.gripper_to(min(world.arm.gripper_open, plan.grasp.width + PRESHAPE), 0.1, ramp_s=0.3)
    cell.gripper_to(world.arm.gripper_closed, 0.4, ramp_s=0.6)  # squeeze gently: a snap shoves the part
    touching = cell.pads_touch(start.body)
    cell.holding = part
    # Awake until the gripper has let go and backed off: asleep against a pad, it would stay there.
    cell.keep_awake(part)
    if cell.recorder is not None:
        cell.recorder.grasped(world, world.data, part)
    return touching


def lift(start: PickStart, plan: GraspPlan, touching_at_close: bool) -> Lifted:
    """Raise the tool straight up by LIFT, and read how far the part came with it."""
    cell = start.cell
    T_lift = shift(plan.T_grasp, [0, 0, LIFT])
    qs = cell.path(plan.q_grasp, plan.T_grasp, T_lift)
    cell.follow(qs, 1.0)
    return Lifted(T_lift, qs[-1], start.risen(), touching_at_close, cell.pads_touch(start.body))


def choose_seat(start: PickStart, plan: GraspPlan, lifted: Lifted) -> Seat:
    """The seat planned with the grasp or, for a part with twins, the one for the way round a look in the
    hand finds it held (kept as planned when no seat that way is reachable)."""
    note = "" if lifted.touching_at_close else "both pads touched only after the lift began; "
    if not start.twins:
        return Seat(plan.place, None, note)
    T_tool_parts = [np.linalg.inv(plan.T_grasp) @ T for T in [start.T_est, *start.twins]]
    seen = look_in_hand(start.cell, start.perception, start.part, lifted.q, lifted.T_tool, T_tool_parts)
    note += seen.summary() + "; "
    if not seen.chosen:
        return Seat(plan.place, seen, note)
    T_part_tool = np.linalg.inv(T_tool_parts[seen.chosen])
    replanned = replan_place(start.cell, start.part, plan.grasp, T_part_tool, lifted.q, plan.T_grasp)
    if replanned is None:  # seated as first planned, rather than dropped from the lift height
        return Seat(plan.place, seen, note + "held the other way round, but no seat for it that way is reachable; ")
    return Seat(replanned, seen, note)


def transport(start: PickStart, lifted: Lifted, seat: Seat) -> Carried:
    """Carry the part at the lift height along an arc about the base to above its seat."""
    cell, place = start.cell, seat.place
    T_above = shift(place.T_place, [0, 0, lifted.T_tool[2, 3] - place.T_place[2, 3]])
    try:
        qs = cell.path(lifted.q, lifted.T_tool, T_above, arc=True)
    except UnreachableTargetError:  # no continuous arc: one joint-space move to the planned configuration
        qs = [place.q_above]
    cell.follow(qs, 2.5)
    return Carried(T_above, qs[-1], bool(cell.pads_touch(start.body) and start.risen() >= MIN_LIFT))


def release(start: PickStart, plan: GraspPlan, seat: Seat, carried: Carried) -> Released:
    """Descend to just above seating and ease the gripper open; the cell no longer holds the part."""
    world, cell, place = start.world, start.cell, seat.place
    # Release just above seating, or higher when the fingers would otherwise land on the fixture's walls
    # or be pinned against them as they open (they stick out past the part along the closing direction).
    wall_top = world.table_top + world.config.fixture_wall[1] + WALL_CLEARANCE
    reach = finger_reach(cell, plan.grasp.width + RELEASE_EASE)
    drop = 0.002 if place.fingers_clear else max(0.002, wall_top - (place.T_place[2, 3] - reach))
    T_release = shift(place.T_place, [0, 0, drop])
    qs = cell.path(carried.q, carried.T_above, T_release)
    cell.follow(qs, 1.2)
    cell.gripper_to(min(world.arm.gripper_open, plan.grasp.width + RELEASE_EASE), 0.3, ramp_s=0.3)
    cell.holding = None
    return Released(T_release, carried.T_above, qs[-1])


def retreat(start: PickStart, released: Released) -> None:
    """Back off to above the seat, open fully, and let the part sleep again."""
    cell = start.cell
    cell.follow(cell.path(released.q, released.T_release, released.T_above), 0.8)
    cell.gripper_to(start.world.arm.gripper_open, 0.3)  # the part has settled ~1.4 s since release
    cell.keep_awake(None)


def judge(start: PickStart, plan: GraspPlan, lifted: Lifted, seat: Seat) -> PickResult:
    """The result of a pick carried through: where the part ended against its fixture or in the tote (truth)."""
    seated = placement(start.cell, start.world, start.part)
    return start.result(plan.grasp.name, True, lifted.height, seated.placed, seated.error_mm, seated.yaw_deg,
                        seat.note + seated.note(), seat.in_hand)


def give_up(start: PickStart, plan: GraspPlan, lifted_m: float, why: str,
            in_hand: InHandLook | None = None) -> PickResult:
    """Open, back the tool off straight up (so the next move sweeps nothing), and report the pick failed."""
    world, cell = start.world, start.cell
    cell.holding = None
    try:
        cell.gripper_to(world.arm.gripper_open, 0.4)
        q = cell.commanded_q()
        T = T_world_site(world.model, world.kinematics(q), world.arm.tool_site)
        cell.follow(cell.path(q, T, shift(T, [0, 0, LIFT])), 0.8)
    except (UnreachableTargetError, WorkspaceBlockedError):
        pass
    cell.keep_awake(None)
    return start.result(plan.grasp.name, False, lifted_m, note=why, in_hand=in_hand)
