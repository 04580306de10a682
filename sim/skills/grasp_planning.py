"""Grasp planning: which of a part's grasps, approached how, reaching which tool poses.

:func:`plan_grasp` takes a part's pose estimate and returns the first of the part's grasps
(``World.grasps``: the catalog's, or those synthesised from a user's mesh, best first) that
is narrower than the gripper, not a thin-wall pinch, approached from above, and whose pre-grasp,
grasp, above-fixture and place poses the IK reaches. The grasps approached most nearly straight down
come first (a part lying any way: those made for the rest it lies in), then those whose fingers fit inside
the fixture's pocket; the others are released above the pocket's walls. Nothing here reads the
simulator's truth: only the estimate, the part's mesh and grasps, and the robot's own kinematics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
import trimesh

from psorr.geometry.rotations import rotation_angle
from sim.control.cell import ArmCell
from sim.errors import UnreachableTargetError
from sim.skills.finger_clearance import approach_opening, fingers_clear_fixture
from sim.skills.grasps import Grasp
from sim.skills.part_geometry import hull_points

PRE_GRASP = 0.10  # m back along -approach before the approach
LIFT = 0.10  # m the tool rises after closing; the transport runs at that height
PAD_CLEARANCE = 0.0015  # m kept between the pads' lower ends and the table when grasping
TOTE_DROP = 0.004  # m above the tote's floor a part is let go: set down, not dropped, yet clear of the floor


def from_above(approach_world: np.ndarray) -> bool:
    """Whether an approach direction (3,; world, unit) comes roughly from above, within about 46 degrees of
    straight down: the table is in the way of any other."""
    return bool(approach_world[2] <= -0.7)


def angle_deg(R: np.ndarray) -> float:
    """Rotation angle (degrees) of a (3, 3) rotation matrix."""
    return float(np.degrees(rotation_angle(R)))


def tool_pose(T_world_part: np.ndarray, grasp, flip: bool) -> np.ndarray:
    """Tool pose (z along the approach, x along closing, optionally both flipped about z) for ``grasp``."""
    z = T_world_part[:3, :3] @ grasp.approach
    x = T_world_part[:3, :3] @ grasp.closing * (-1.0 if flip else 1.0)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = T_world_part[:3, :3] @ grasp.point + T_world_part[:3, 3]
    return T


def shift(T: np.ndarray, offset) -> np.ndarray:
    T = T.copy()
    T[:3, 3] = T[:3, 3] + offset
    return T


@dataclass(frozen=True, eq=False)
class PlacePlan:
    """A reachable seat for the held part: the tool pose (4, 4, world) that seats it in its fixture, the
    joints (nq,) above that at the transport height, and whether the fingers fit inside the fixture's
    pocket there (if not, the part is released above the pocket's walls)."""

    T_place: np.ndarray
    q_above: np.ndarray
    fingers_clear: bool


@dataclass(frozen=True, eq=False)
class GraspPlan:
    """A reachable grasp: the tool pose (4, 4, world) at the grasp, the joints (nq,) at the pre-grasp and at
    the grasp, where the part is seated, and how far (m) the pads are opened on the way down (the gripper's
    widest, unless that would land the fingers on a fixture or the tote)."""

    grasp: Grasp
    T_grasp: np.ndarray
    q_pre: np.ndarray
    q_grasp: np.ndarray
    place: PlacePlan
    approach_opening: float


@dataclass(frozen=True)
class NoGrasp:
    """Why no grasp of a part could be planned: a reason per grasp tried, "; "-joined."""

    why: str


@dataclass(frozen=True, eq=False)
class SeatOption:
    """One way to seat a held part: the tool pose (4, 4, world) in the fixture, whether the fingers clear
    the fixture's walls there, and the wrist's turn (deg) from the grasp (the less, the better)."""

    T_place: np.ndarray
    fingers_clear: bool
    turn_deg: float


def plan_grasp(cell: ArmCell, part: str, T_est: np.ndarray) -> GraspPlan | NoGrasp:
    """The first reachable grasp: the most nearly straight down first, then those whose fingers fit the fixture's
    pocket, then in the part's order."""
    world = cell.world
    info = world.catalog[part]
    to_tote = world.places.get(part) == "tote"
    T_fix = None if to_tote else world.T_world_fixtures[part]
    # Plan from home whatever the arm's pose: from the look pose, panned aside, the local IK can
    # wander into a wound-up configuration the arm cannot get to.
    q0 = cell.data.qpos.copy()
    q0[cell.qadr] = cell.model.key(cell.cfg.home_key).qpos[cell.qadr]
    reasons, candidates = [], []
    for index, grasp in enumerate(world.grasps[part]):
        if grasp.width >= world.arm.max_opening:
            reasons.append(f"{grasp.name}: {grasp.width * 1e3:.0f} mm too wide")
            continue
        if grasp.width < 0.008:
            # A pinch on a thin wall: the pads' own width would straddle the wall's neighbours.
            reasons.append(f"{grasp.name}: pinch of {grasp.width * 1e3:.1f} mm not attempted")
            continue
        approach_w = T_est[:3, :3] @ grasp.approach
        if not from_above(approach_w):
            reasons.append(f"{grasp.name}: approach not from above")
            continue
        for flip in (False, True):
            T_grasp = tool_pose(T_est, grasp, flip)
            # Keep the pads' lower ends off the table: grasp higher on the same faces if need be.
            short = world.table_top + PAD_CLEARANCE - (T_grasp[2, 3] - cell.pad_reach)
            if short > 0:
                if _above_the_top(world, part, info, grasp, T_est, T_grasp, short, world.config.resting == "any",
                                  cell.pad_reach):
                    reasons.append(f"{grasp.name}: the pads would hit the table")
                    break
                T_grasp = shift(T_grasp, [0, 0, short])
            T_part_tool = np.linalg.inv(T_est) @ T_grasp
            seats = [tote_seat(world, part, T_est, T_part_tool)] if to_tote else \
                seat_options(cell, info, T_fix, T_part_tool, grasp.width, T_grasp)
            # The most upright approach first: a part lying any way has grasps for each of its rests, and those
            # of the rest it lies in approach straight down; another rest's, tilted, may close on air.
            tilt = float(approach_w[2])
            for seat in seats:
                candidates.append(((tilt, not seat.fingers_clear, index, seat.turn_deg), grasp, flip, T_grasp, seat))
    candidates.sort(key=lambda c: c[0])
    for _, grasp, flip, T_grasp, seat in candidates:
        T_place = seat.T_place
        try:
            q_pre = cell.solve(q0, shift(T_grasp, PRE_GRASP * -T_grasp[:3, 2]))
            q_grasp = cell.solve(q_pre, T_grasp)
            T_above = shift(T_place, [0, 0, T_grasp[2, 3] + LIFT - T_place[2, 3]])
            q_above = cell.solve(q_grasp, T_above)
            q_place = cell.solve(q_above, T_place)
        except UnreachableTargetError as exc:
            reasons.append(f"{grasp.name}{' flipped' if flip else ''}: {exc}")
            continue
        problem = next(filter(None, (configuration_problem(cell, q) for q in (q_pre, q_grasp, q_above, q_place))), "")
        opening = None
        if not problem:
            opening, problem = approach_opening(cell, q_grasp, grasp.width)
        if problem:
            reasons.append(f"{grasp.name}{' flipped' if flip else ''}: {problem}")
            continue
        return GraspPlan(grasp, T_grasp, q_pre, q_grasp, PlacePlan(T_place, q_above, seat.fingers_clear), opening)
    return NoGrasp("; ".join(reasons) or "the part has no grasps")


def _above_the_top(world, part: str, info, grasp: Grasp, T_est: np.ndarray, T_grasp: np.ndarray, short: float,
                   any_way: bool, pad_reach: float) -> bool:
    """Whether raising the grasp by ``short`` (m) to keep the pads off the table would put it within 2 mm of the
    part's top (the model's top for a part resting upright), or, for a part resting any way, the pads' lower ends
    (``pad_reach`` below the tool) within 2 mm of its hull's highest point at ``T_est``."""
    if not any_way:
        return grasp.point[2] + short > info.bounds()[1, 2] - 0.002
    # A synthesised grasp may hold a low part by the pads' lower ends: only they must still reach its sides.
    return T_grasp[2, 3] + short - pad_reach > float(hull_points(world, T_est, part)[:, 2].max()) - 0.002


def tote_seat(world, part: str, T_est: np.ndarray, T_part_tool: np.ndarray) -> SeatOption:
    """The tool pose that sets the held part down in its slot of the tote as it lay on the table, turned about
    the vertical (by the least turn) so that its footprint's long side lies along the tote's x, its footprint's
    centre over the slot and ``TOTE_DROP`` above the floor."""
    corners = hull_points(world, T_est, part)
    T_rect, sides = trimesh.bounds.oriented_bounds_2D(corners[:, :2])
    long_axis = T_rect[0, :2] if sides[0] >= sides[1] else T_rect[1, :2]
    tote_x = world.T_world_tote[:2, 0]
    turn = math.atan2(tote_x[1], tote_x[0]) - math.atan2(long_axis[1], long_axis[0])
    turn = (turn + math.pi / 2) % math.pi - math.pi / 2  # a rectangle is the same turned by half a turn
    centre = np.linalg.solve(T_rect[:2, :2], -T_rect[:2, 2])  # the rectangle's centre, world x, y
    slot = world.T_world_tote[:3, :3] @ np.append(world.tote.slots[part], 0.0) + world.T_world_tote[:3, 3]
    R = np.array([[math.cos(turn), -math.sin(turn), 0.0], [math.sin(turn), math.cos(turn), 0.0], [0.0, 0.0, 1.0]])
    T_target = T_est.copy()
    T_target[:3, :3] = R @ T_est[:3, :3]
    T_target[:2, 3] = slot[:2] + R[:2, :2] @ (T_est[:2, 3] - centre)
    T_target[2, 3] += world.table_top + TOTE_DROP - corners[:, 2].min()
    return SeatOption(T_target @ T_part_tool, True, abs(math.degrees(turn)))


def seat_options(cell: ArmCell, info, T_fix: np.ndarray, T_part_tool: np.ndarray, width: float,
                 T_grasp: np.ndarray) -> list[SeatOption]:
    """The tool poses (4, 4, world) that seat a part held at ``T_part_tool`` (the tool in the part's frame)
    in its fixture ``T_fix``, one per symmetry of the part whose tool approach points down; each with
    whether the fingers clear the fixture's walls, and the wrist's turn (deg) from ``T_grasp``."""
    out = []
    for S in info.symmetries:
        T_place = T_fix @ S @ T_part_tool
        if not from_above(T_place[:3, 2]):
            continue
        clears = fingers_clear_fixture(cell, info, S @ T_part_tool, width)
        out.append(SeatOption(T_place, clears, angle_deg(T_grasp[:3, :3].T @ T_place[:3, :3])))
    return out


def replan_place(cell: ArmCell, part: str, grasp: Grasp, T_part_tool: np.ndarray, q_start: np.ndarray,
                 T_grasp: np.ndarray) -> PlacePlan | None:
    """For a part found, once in the hand, to be held at ``T_part_tool`` rather than as planned: the seat
    that clears the fixture's walls and turns the wrist least among the reachable ones (the joints above
    it solved from ``q_start``); None if no seat is reachable."""
    world = cell.world
    info = world.catalog[part]
    options = seat_options(cell, info, world.T_world_fixtures[part], T_part_tool, grasp.width, T_grasp)
    for seat in sorted(options, key=lambda o: (not o.fingers_clear, o.turn_deg)):
        T_place = seat.T_place
        try:
            T_above = shift(T_place, [0, 0, T_grasp[2, 3] + LIFT - T_place[2, 3]])
            q_above = cell.solve(q_start, T_above)
            q_place = cell.solve(q_above, T_place)
        except UnreachableTargetError:
            continue
        if not (configuration_problem(cell, q_above) or configuration_problem(cell, q_place)):
            return PlacePlan(T_place, q_above, seat.fingers_clear)
    return None


def configuration_problem(cell: ArmCell, q: np.ndarray) -> str:
    """Why the arm should not go to ``q`` (nq,), or "" if it may.

    The IK is local: from some starts it converges to a wound-up configuration (the upper arm
    swung down behind the base) whose tool pose is right but which the arm can only reach by
    sweeping through the table. Such solutions, and any whose links (pads and fingers aside,
    which belong near the part) touch the table, a part or a fixture, are refused.
    """
    lift = float(q[cell.qadr[1]])
    if not -math.pi <= lift <= 0.0:
        return f"wound-up arm (shoulder lift {math.degrees(lift):.0f} deg, outside [-180, 0])"
    model = cell.model
    data = cell.world.kinematics(q)
    tool_z = float(data.site_xpos[model.site(cell.cfg.tool_site).id][2])
    if tool_z < cell.world.table_top:  # a link through the table can escape the contact test below
        return f"the tool would be {1e3 * (cell.world.table_top - tool_z):.0f} mm under the table top"
    mujoco.mj_collision(model, data)
    links = {model.geom(g).id for g in cell.cfg.collision_geoms} - set(cell.pads) - cell.finger_geoms
    for contact in data.contact[: data.ncon]:
        pair = {contact.geom1, contact.geom2}
        if pair & links and not pair <= links and contact.dist < 0:
            other = (pair - links).pop()
            return f"the arm would touch {model.geom(other).name or model.body(model.geom_bodyid[other]).name}"
    return ""


def upright_equivalent(T_est: np.ndarray, info) -> np.ndarray:
    """The estimate re-expressed by the part's symmetry whose +z points most nearly up.

    A recogniser may return any of a symmetric part's equivalent poses (a
    transformer flipped 180 deg about its centre is the same transformer);
    planning needs the one that stands on its resting face.
    """
    candidates = [T_est @ S for S in info.symmetries]
    return max(candidates, key=lambda T: (round(float(T[2, 2]), 6), -float(T[2, 3])))


