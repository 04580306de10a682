"""Judging a pick on the simulator's truth: what it achieved (:class:`PickResult`), how far the pose it was
planned from was off, and whether the part ended seated in its fixture.

Every check here reads the simulator's body poses, never the plan; :mod:`sim.skills.pick` calls them
before and after it moves the part.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from psorr.synthetic.catalog import symmetry_transforms
from sim.skills.grasp_planning import angle_deg, upright_equivalent
from sim.skills.in_hand import InHandLook
from sim.skills.part_geometry import hull_points, lowest_point
from sim.world import World
from sim.world.tote import ToteLayout

if TYPE_CHECKING:
    from sim.control.cell import ArmCell

MIN_LIFT = 0.05  # m the part must rise to count as grasped
PLACE_TOL_MM = 5.0
PLACE_TOL_DEG = 3.0
REST_TOL_MM = 3.0  # the seated part's origin (its resting face) within this of the table top
AT_REST_MM_S = 1.0  # a part moving slower than this is at rest
TOTE_SETTLE_S = 0.5  # s a part set down in the tote is left before it is judged at rest
# s at most it is left to come to rest: a part set down leaning on a wall slides down it for a while
TOTE_SETTLE_MAX_S = 2.0
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


@dataclass(frozen=True)
class Seating:
    """Where a released part ended against its fixture (truth; mm and degrees, least over its symmetries).

    Attributes:
        error_mm: distance of its origin from the fixture's; xy_mm: of that, in the table plane.
        yaw_deg, tilt_deg: its turn about the vertical, and its tilt, against the fixture's frame.
        above_table_mm: height of its origin (its resting face) above the table top.
        placed: within PLACE_TOL_MM and PLACE_TOL_DEG of yaw, and resting on the table (within
            REST_TOL_MM of it, tilted at most PLACE_TOL_DEG).
    """

    error_mm: float
    xy_mm: float
    yaw_deg: float
    tilt_deg: float
    above_table_mm: float
    placed: bool

    def note(self) -> str:
        """One line for the pick's note, "placed: ..." or "not seated: ..."."""
        verdict = "placed" if self.placed else "not seated"
        return (f"{verdict}: {self.error_mm:.1f} mm (xy {self.xy_mm:.1f}), yaw {self.yaw_deg:.1f} deg, "
                f"tilt {self.tilt_deg:.1f} deg, z {self.above_table_mm:+.1f} mm over the table")


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


def seating(world: World, part: str) -> Seating:
    """Where ``part`` is now against its fixture, read from ``world.data``."""
    T_final, T_fixture = world.body_pose(part), world.T_world_fixtures[part]
    error, yaw, tilt = fixture_error(T_final, T_fixture, world.catalog[part])
    xy = float(np.linalg.norm(T_final[:2, 3] - T_fixture[:2, 3])) * 1e3
    rests = abs(T_final[2, 3] - world.table_top) * 1e3 <= REST_TOL_MM and tilt <= PLACE_TOL_DEG
    placed = bool(error <= PLACE_TOL_MM and yaw <= PLACE_TOL_DEG and rests)  # not numpy.bool_: JSON wrote 0.0
    return Seating(error, xy, yaw, tilt, 1e3 * (T_final[2, 3] - world.table_top), placed)


def resting_on_table(world: World, T_world_part: np.ndarray, part: str) -> bool:
    """Whether a pose of ``part`` could be resting on the table, its origin over the table: upright (one of its
    symmetric equivalents has its origin, on its resting face, within ``REST_TOL`` of the table top and tilts
    at most ``REST_TILT_DEG``) or, in a world where parts rest any way, with its lowest point within
    ``REST_TOL`` of the table top."""
    hx, hy = (v / 2 for v in world.config.table_size)
    if abs(T_world_part[0, 3]) > hx or abs(T_world_part[1, 3]) > hy:
        return False
    if world.config.resting == "any":
        return abs(lowest_point(world, T_world_part, part) - world.table_top) <= REST_TOL
    T = upright_equivalent(np.asarray(T_world_part, dtype=float), world.catalog[part])
    return abs(T[2, 3] - world.table_top) <= REST_TOL and T[2, 2] >= math.cos(math.radians(REST_TILT_DEG))


def not_resting_note(world: World, T_est: np.ndarray) -> str:
    """Why no pick was planned from an upright estimate that does not rest on the table."""
    tilt = math.degrees(math.acos(np.clip(T_est[2, 2], -1, 1)))
    return (f"estimate not resting upright on the table (z {T_est[2, 3] - world.table_top:+.3f} m above it, "
            f"tilted {tilt:.0f} deg): no pick planned")


@dataclass(frozen=True)
class ToteSeating:
    """Where a released part ended in the tote (truth): ``inside`` (every corner of its hull within the tote's
    walls, up to REST_TOL_MM and the walls' inner half, as its lowest point is judged against the floor),
    ``lowest_mm`` its lowest point over the table, ``speed_mm_s`` its speed, and ``slot_mm`` its origin's
    distance from its slot in the table plane."""

    inside: bool
    lowest_mm: float
    speed_mm_s: float
    slot_mm: float

    @property
    def error_mm(self) -> float:
        return self.slot_mm

    @property
    def yaw_deg(self) -> float:
        """No yaw is asked of a part in the tote."""
        return math.nan

    @property
    def placed(self) -> bool:
        """Inside the tote, down on its floor (within REST_TOL_MM), and at rest (under AT_REST_MM_S)."""
        return bool(self.inside and abs(self.lowest_mm) <= REST_TOL_MM and self.speed_mm_s < AT_REST_MM_S)

    def note(self) -> str:
        verdict = "placed in the tote" if self.placed else "not placed in the tote"
        return (f"{verdict}: {'inside' if self.inside else 'outside'} its walls, {self.slot_mm:.0f} mm from its "
                f"slot, lowest point {self.lowest_mm:+.1f} mm over the table, moving {self.speed_mm_s:.1f} mm/s")


def inside_walls(tote: ToteLayout, xy_in_tote: np.ndarray, wall: float) -> bool:
    """Whether the tote-frame points (N, 2) of a part lie inside the walls (``wall`` metres thick) of ``tote``."""
    # A part at rest against a wall presses into it by the contact's give, as it does into the floor: an
    # extruder body lying against the inside of the wall was judged outside by 0.1 mm. Within the wall's
    # inner half it cannot be a part outside the tote.
    return tote.holds(xy_in_tote, margin=min(REST_TOL_MM / 1e3, wall / 2))


def tote_seating(world: World, part: str) -> ToteSeating:
    """Where ``part`` is now against the tote, read from ``world.data``."""
    T = world.body_pose(part)
    T_tote_world = np.linalg.inv(world.T_world_tote)
    corners = hull_points(world, T, part) @ T_tote_world[:3, :3].T + T_tote_world[:3, 3]
    slot = world.tote.slots[part]
    adr = world.model.jnt_dofadr[world.model.joint(f"{part}_joint").id]
    speed = float(np.linalg.norm(world.data.qvel[adr:adr + 3])) * 1e3
    origin = T_tote_world[:2, :3] @ T[:3, 3] + T_tote_world[:2, 3]
    inside = inside_walls(world.tote, corners[:, :2], world.config.tote_wall[0])
    return ToteSeating(inside, corners[:, 2].min() * 1e3, speed, float(np.linalg.norm(origin - slot)) * 1e3)


def tote_seating_at_rest(cell: ArmCell, world: World, part: str) -> ToteSeating:
    """Where ``part`` lies in the tote once at rest: ``cell`` is held TOTE_SETTLE_S, then on until the part
    moves slower than AT_REST_MM_S, for TOTE_SETTLE_MAX_S in all at most."""
    cell.hold(TOTE_SETTLE_S)
    waited, seated = TOTE_SETTLE_S, tote_seating(world, part)
    while seated.speed_mm_s >= AT_REST_MM_S and waited < TOTE_SETTLE_MAX_S:
        cell.hold(0.1)
        waited, seated = waited + 0.1, tote_seating(world, part)
    return seated


def placement(cell: ArmCell, world: World, part: str) -> Seating | ToteSeating:
    """Where ``part`` is now against its place: its fixture, or the tote once it is at rest there
    (:func:`tote_seating_at_rest`, holding ``cell``), read from ``world.data``."""
    return tote_seating_at_rest(cell, world, part) if world.places.get(part) == "tote" else seating(world, part)
