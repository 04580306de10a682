"""Pick-and-place episodes in the robot cell: grasp each workpiece and seat it in its fixture.

:func:`pick_and_place` plans a grasp from a pose estimate of one part (the catalog's grasps in
order, those narrower than the gripper and not thin-wall pinches, approached from above, whose
pre-grasp, grasp, above-fixture and place poses the IK reaches; grasps whose pads fit inside the
fixture's pocket first, the others are released above the pocket's walls), then executes it by
ramping the arm's position targets while stepping the simulation: pre-grasp (``PRE_GRASP`` back
along the approach), approach, close, lift, transport above the fixture, descend, open, retreat.
Every success check reads the simulator's truth (contacts and body poses), never the plan.

:func:`run_episode` does this for each workpiece, with the true poses (``"oracle"``) or with the
poses PSORR recognises in the Kinect's cloud (``"recognized"``); a part the recognizer did not
return is not picked.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import mujoco
import numpy as np

from psorr.errors import InvalidInputError
from psorr.workpieces import symmetry_transforms
from sim.ik import ArmIK, T_world_site, UnreachableTargetError
from sim.world import World

PRE_GRASP = 0.10  # m back along -approach before the approach
LIFT = 0.10  # m the tool rises after closing; the transport runs at that height
MIN_LIFT = 0.05  # m the part must rise to count as grasped
PLACE_TOL_MM = 5.0
PLACE_TOL_DEG = 3.0
REST_TOL_MM = 3.0  # the seated part's origin (its resting face) within this of the table top
RAMP_S = 0.8  # s a move's joint-space ramp lasts
SETTLE_S = 0.3  # s held at the goal after each move
PAD_CLEARANCE = 0.0015  # m kept between the pads' lower ends and the table when grasping
WALL_CLEARANCE = 0.002  # m between the pads' lower ends and the fixture walls' tops at release
CART_STEP = 0.03  # m between IK waypoints of a straight-line tool move


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
        pose_error_mm, rot_error_deg: the pose estimate used against the true start pose (0 for the oracle).
        note: what happened, for the log.
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


@dataclass(frozen=True)
class EpisodeResult:
    """One :class:`PickResult` per workpiece, in the world's order, and the episode's wall time (s)."""

    picks: tuple[PickResult, ...]
    wall_s: float


# ---------------------------------------------------------------------------------------------- helpers

def _angle_deg(R: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))))


def pose_error(T_est: np.ndarray, T_true: np.ndarray, info) -> tuple[float, float]:
    """(mm, deg): position and rotation error of ``T_est`` against ``T_true``, least over the symmetries."""
    best = (math.inf, math.inf)
    for S in symmetry_transforms(info):
        T = T_true @ S
        e = (float(np.linalg.norm(T_est[:3, 3] - T[:3, 3])) * 1e3, _angle_deg(T_est[:3, :3].T @ T[:3, :3]))
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


def _tool_pose(T_world_part: np.ndarray, grasp, flip: bool) -> np.ndarray:
    """Tool pose (z along the approach, x along closing, optionally both flipped about z) for ``grasp``."""
    z = T_world_part[:3, :3] @ grasp.approach
    x = T_world_part[:3, :3] @ grasp.closing * (-1.0 if flip else 1.0)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = T_world_part[:3, :3] @ grasp.point + T_world_part[:3, 3]
    return T


def _shift(T: np.ndarray, offset) -> np.ndarray:
    T = T.copy()
    T[:3, 3] = T[:3, 3] + offset
    return T


class _Cell:
    """The arm's handles in a world and the stepping of ramped moves."""

    def __init__(self, world: World):
        m, cfg = world.model, world.arm
        self.world, self.model, self.data, self.cfg = world, m, world.data, cfg
        self.ik = _ik_for(world)
        self.act = np.array([m.actuator(a).id for a in cfg.arm_actuators])
        self.qadr = np.array([m.joint(j).qposadr[0] for j in cfg.arm_joints])
        self.gripper = m.actuator(cfg.gripper_actuator).id
        self.pads = [m.geom(g).id for g in cfg.pad_geoms]
        # The pads are centred on the tool site along its z: they reach this far beyond it.
        self.pad_reach = float(max(m.geom_size[p][2] for p in self.pads))
        self.table = ["table_collision"]
        self.steps = 0

    def step(self, n: int) -> None:
        for _ in range(n):
            mujoco.mj_step(self.model, self.data)
        self.steps += n

    def solve(self, q_start: np.ndarray, T: np.ndarray, avoid_table: bool = False) -> np.ndarray:
        pairs = [(self.cfg.collision_geoms, self.table)] if avoid_table else None
        try:
            return np.array(self.ik.solve(q_start, T, collision_geoms=pairs).q)
        except UnreachableTargetError:  # the local solver can stall far from home: retry from home
            q_home = np.array(q_start, dtype=float)
            q_home[self.qadr] = self.model.key(self.cfg.home_key).qpos[self.qadr]
            return np.array(self.ik.solve(q_home, T, collision_geoms=pairs).q)

    def move_joints(self, goal_arm: np.ndarray, ramp_s: float = RAMP_S, settle_s: float = SETTLE_S) -> None:
        """Ramp the arm's position targets from their current values to ``goal_arm`` (6,), then hold."""
        dt = self.model.opt.timestep
        start = self.data.ctrl[self.act].copy()
        n = max(1, round(ramp_s / dt))
        for i in range(n):
            s = (i + 1) / n
            s = s * s * (3 - 2 * s)  # smoothstep
            self.data.ctrl[self.act] = start + s * (goal_arm - start)
            self.step(1)
        self.step(round(settle_s / dt))

    def path(self, q_start: np.ndarray, T_from: np.ndarray, T_to: np.ndarray, arc: bool = False) -> list[np.ndarray]:
        """IK configurations along a tool path from ``T_from`` to ``T_to``, orientation slerped.

        The path is a straight line, or with ``arc`` an arc about the arm's base axis (radius, angle
        and height interpolated), which keeps a long transport clear of the base's singular column.
        """
        from scipy.spatial.transform import Rotation, Slerp

        base = self.world.T_world_arm_base[:3, 3]
        a, b = T_from[:3, 3] - base, T_to[:3, 3] - base
        ra, rb = math.hypot(a[0], a[1]), math.hypot(b[0], b[1])
        pa, pb = math.atan2(a[1], a[0]), math.atan2(b[1], b[0])
        dp = (pb - pa + math.pi) % (2 * math.pi) - math.pi
        length = (abs(dp) * max(ra, rb) + abs(rb - ra) + abs(b[2] - a[2])) if arc else float(np.linalg.norm(b - a))
        n = max(1, math.ceil(length / CART_STEP))
        slerp = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([T_from[:3, :3], T_to[:3, :3]])))
        q, out = q_start, []
        for i in range(1, n + 1):
            s = i / n
            T = np.eye(4)
            T[:3, :3] = slerp([s]).as_matrix()[0]
            if arc:
                r, phi = ra + s * (rb - ra), pa + s * dp
                T[:3, 3] = base + [r * math.cos(phi), r * math.sin(phi), a[2] + s * (b[2] - a[2])]
            else:
                T[:3, 3] = T_from[:3, 3] + s * (T_to[:3, 3] - T_from[:3, 3])
            q = self.solve(q, T)
            out.append(q)
        return out

    def follow(self, qs: list[np.ndarray], seconds: float) -> None:
        for k, q in enumerate(qs):
            last = k == len(qs) - 1
            self.move_joints(q[self.qadr], ramp_s=seconds / len(qs), settle_s=SETTLE_S if last else 0.0)

    def gripper_to(self, opening: float, seconds: float = 0.6, ramp_s: float = 0.0) -> None:
        """Ramp the gripper command linearly to ``opening`` over ``ramp_s``, then hold for ``seconds``."""
        dt = self.model.opt.timestep
        start, n = float(self.data.ctrl[self.gripper]), round(ramp_s / dt)
        for i in range(n):
            self.data.ctrl[self.gripper] = start + (i + 1) / n * (opening - start)
            self.step(1)
        self.data.ctrl[self.gripper] = opening
        self.step(round(seconds / dt))

    def pads_touch(self, body: int) -> bool:
        touched = set()
        for c in self.data.contact[: self.data.ncon]:
            for a, b in ((c.geom1, c.geom2), (c.geom2, c.geom1)):
                if a in self.pads and self.model.geom_bodyid[b] == body:
                    touched.add(a)
        return len(touched) == len(self.pads)


_BOUNDS: dict[str, np.ndarray] = {}


def _bounds(info) -> np.ndarray:
    """(2, 3) model-frame bounds of the part's mesh (lo, hi)."""
    if info.name not in _BOUNDS:
        _BOUNDS[info.name] = np.asarray(info.load_mesh().bounds, dtype=float)
    return _BOUNDS[info.name]


def _kinematics(world: World, q: np.ndarray) -> mujoco.MjData:
    data = mujoco.MjData(world.model)
    data.qpos[:] = q
    mujoco.mj_kinematics(world.model, data)
    return data


_IK_CACHE: dict[int, ArmIK] = {}


def _ik_for(world: World) -> ArmIK:
    key = id(world.model)
    if key not in _IK_CACHE:
        _IK_CACHE.clear()
        _IK_CACHE[key] = ArmIK(world.model, world.arm)
    return _IK_CACHE[key]


# ---------------------------------------------------------------------------------------------- planning

@dataclass(frozen=True)
class _Plan:
    grasp: object
    T_grasp: np.ndarray
    T_place: np.ndarray
    q_pre: np.ndarray
    q_grasp: np.ndarray
    q_place_above: np.ndarray
    pads_clear_fixture: bool  # the pads fit inside the pocket when the part is seated


def _pads_clear_fixture(cell: _Cell, info, T_fix_tool: np.ndarray, width: float) -> bool:
    """Whether both pads, closed to ``width`` around the seated part, stay inside the fixture's pocket
    (or above its walls); ``T_fix_tool`` is the tool pose in the fixture frame."""
    cfg = cell.world.config
    hx, hy, hz = (float(v) for v in cell.model.geom_size[cell.pads[0]])
    lo = _bounds(info)[0, :2] - cfg.fixture_clearance
    hi = _bounds(info)[1, :2] + cfg.fixture_clearance
    for side in (-1.0, 1.0):
        cx = side * (width / 2 + hx)
        corners = np.array([[cx + a * hx, b * hy, c * hz, 1.0] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)])
        pts = corners @ T_fix_tool.T
        low = pts[:, 2] < cfg.fixture_wall[1] + WALL_CLEARANCE
        if np.any(low & np.any((pts[:, :2] < lo) | (pts[:, :2] > hi), axis=1)):
            return False
    return True


def _plan(cell: _Cell, part: str, T_est: np.ndarray) -> tuple[_Plan | None, str]:
    """The first reachable grasp, in catalog order, preferring those whose pads fit the fixture's pocket."""
    world = cell.world
    info = world.catalog[part]
    T_fix = world.T_world_fixtures[part]
    q0 = cell.data.qpos.copy()
    reasons, candidates = [], []
    for index, grasp in enumerate(info.grasps):
        if grasp.width >= world.arm.max_opening:
            reasons.append(f"{grasp.name}: {grasp.width * 1e3:.0f} mm too wide")
            continue
        if grasp.width < 0.008:
            # A pinch on a thin wall: the pads' own width would straddle the wall's neighbours.
            reasons.append(f"{grasp.name}: pinch of {grasp.width * 1e3:.1f} mm not attempted")
            continue
        approach_w = T_est[:3, :3] @ grasp.approach
        if approach_w[2] > -0.7:  # only roughly top-down approaches: the table is in the way otherwise
            reasons.append(f"{grasp.name}: approach not from above")
            continue
        for flip in (False, True):
            T_grasp = _tool_pose(T_est, grasp, flip)
            # Keep the pads' lower ends off the table: grasp higher on the same faces if need be.
            short = world.table_top + PAD_CLEARANCE - (T_grasp[2, 3] - cell.pad_reach)
            if short > 0:
                if grasp.point[2] + short > _bounds(info)[1, 2] - 0.002:
                    reasons.append(f"{grasp.name}: the pads would hit the table")
                    break
                T_grasp = _shift(T_grasp, [0, 0, short])
            T_part_tool = np.linalg.inv(T_est) @ T_grasp
            for S in info.symmetries:
                T_place = T_fix @ S @ T_part_tool
                if T_place[2, 2] > -0.7:
                    continue
                clears = _pads_clear_fixture(cell, info, S @ T_part_tool, grasp.width)
                turn = _angle_deg(T_grasp[:3, :3].T @ T_place[:3, :3])  # prefer the wrist turning least
                candidates.append(((not clears, index, turn), grasp, flip, T_grasp, T_place, clears))
    candidates.sort(key=lambda c: c[0])
    for _, grasp, flip, T_grasp, T_place, clears in candidates:
        try:
            q_pre = cell.solve(q0, _shift(T_grasp, PRE_GRASP * -T_grasp[:3, 2]))
            q_grasp = cell.solve(q_pre, T_grasp)
            T_above = _shift(T_place, [0, 0, T_grasp[2, 3] + LIFT - T_place[2, 3]])
            q_above = cell.solve(q_grasp, T_above)
            cell.solve(q_above, T_place)
        except UnreachableTargetError as exc:
            reasons.append(f"{grasp.name}{' flipped' if flip else ''}: {exc}")
            continue
        return _Plan(grasp, T_grasp, T_place, q_pre, q_grasp, q_above, clears), ""
    return None, "; ".join(reasons) or "the part has no grasps"


# ---------------------------------------------------------------------------------------------- execution

def _upright_equivalent(T_est: np.ndarray, info) -> np.ndarray:
    """The estimate re-expressed by the part's symmetry whose +z points most nearly up.

    A recogniser may return any of a symmetric part's equivalent poses (a
    transformer flipped 180 deg about its centre is the same transformer);
    planning needs the one that stands on its resting face.
    """
    candidates = [T_est @ S for S in info.symmetries]
    return max(candidates, key=lambda T: (round(float(T[2, 2]), 6), -float(T[2, 3])))


def pick_and_place(world: World, part: str, T_world_part_estimate: np.ndarray,
                   rng: np.random.Generator | None = None) -> PickResult:
    """Pick ``part`` using the pose estimate and seat it in its fixture; checks read the simulator.

    ``world.data`` is stepped in place (the arm ends retreated above the fixture). ``rng`` is
    accepted for the API's sake; the execution is deterministic.
    """
    if part not in world.workpieces:
        raise InvalidInputError(f"unknown part {part!r}; the world has {list(world.workpieces)}")
    if part not in world.T_world_fixtures:
        raise InvalidInputError(f"{part} has no fixture: build the world with fixtures=True")
    cell = _Cell(world)
    info = world.catalog[part]
    T_est = _upright_equivalent(np.asarray(T_world_part_estimate, float), info)
    body = world.model.body(part).id
    mujoco.mj_forward(world.model, world.data)
    T_start = world.body_pose(part)
    pos_mm, rot_deg = pose_error(T_est, T_start, info)

    def result(grasp="", grasped=False, lifted=0.0, placed=False, pe=math.nan, pd=math.nan, note=""):
        return PickResult(part, grasp, grasped, float(lifted), placed, float(pe), float(pd), pos_mm, rot_deg, note)

    if abs(T_est[2, 3] - world.table_top) > 0.02 or T_est[2, 2] < math.cos(math.radians(20)):
        return result(note=f"estimate not resting upright on the table (z {T_est[2, 3] - world.table_top:+.3f} m "
                           f"above it, tilted {math.degrees(math.acos(np.clip(T_est[2, 2], -1, 1))):.0f} deg): "
                           "no pick planned")
    plan, why = _plan(cell, part, T_est)
    if plan is None:
        return result(note=f"no reachable grasp: {why}")
    g = plan.grasp
    approach_w = plan.T_grasp[:3, 2]

    def give_up(lifted: float, why: str) -> PickResult:
        """Open, back the tool off straight up (so the next move sweeps nothing), report."""
        cell.gripper_to(world.arm.gripper_open, 0.4)
        q = world.data.qpos.copy()
        q[cell.qadr] = world.data.ctrl[cell.act]  # the commanded joints, not the sagging ones
        T = T_world_site(world.model, _kinematics(world, q), world.arm.tool_site)
        try:
            cell.follow(cell.path(q, T, _shift(T, [0, 0, LIFT])), 0.8)
        except UnreachableTargetError:
            pass
        return result(g.name, False, lifted, note=why)

    cell.gripper_to(world.arm.gripper_open, 0.2)
    # Pre-grasp in joint space, then a straight approach.
    cell.move_joints(plan.q_pre[cell.qadr], ramp_s=1.5)
    T_pre = _shift(plan.T_grasp, -PRE_GRASP * approach_w)
    cell.follow(cell.path(plan.q_pre, T_pre, plan.T_grasp), 1.0)
    cell.gripper_to(min(world.arm.gripper_open, g.width + 0.006), 0.1, ramp_s=0.3)
    cell.gripper_to(world.arm.gripper_closed, 0.4, ramp_s=0.6)  # squeeze gently: a snap shoves the part
    touching = cell.pads_touch(body)
    # Lift straight up.
    T_lift = _shift(plan.T_grasp, [0, 0, LIFT])
    qs = cell.path(plan.q_grasp, plan.T_grasp, T_lift)
    cell.follow(qs, 1.0)
    lifted = float(world.body_pose(part)[2, 3] - T_start[2, 3])
    held = cell.pads_touch(body)
    if not (held and lifted >= MIN_LIFT):
        return give_up(lifted, f"grasp failed: both pads on the part at closing {touching}, "
                               f"after the lift {held}; lifted {lifted * 100:.1f} cm")
    grip = "" if touching else "both pads touched only after the lift began; "
    # Transport at the lift height along an arc about the base, then descend.
    T_above = _shift(plan.T_place, [0, 0, T_lift[2, 3] - plan.T_place[2, 3]])
    try:
        qs = cell.path(qs[-1], T_lift, T_above, arc=True)
    except UnreachableTargetError:  # no continuous arc: one joint-space move to the planned configuration
        qs = [plan.q_place_above]
    cell.follow(qs, 2.5)
    if not (cell.pads_touch(body) and world.body_pose(part)[2, 3] - T_start[2, 3] >= MIN_LIFT):
        return give_up(lifted, "dropped during transport")
    # Release just above seating, or higher when the pads would otherwise land on the fixture's walls
    # (they stick out past the part along the closing direction, further than the pocket's clearance).
    wall_top = world.table_top + world.config.fixture_wall[1] + WALL_CLEARANCE
    drop = 0.002 if plan.pads_clear_fixture else max(0.002, wall_top - (plan.T_place[2, 3] - cell.pad_reach))
    T_release = _shift(plan.T_place, [0, 0, drop])
    qs = cell.path(qs[-1], T_above, T_release)
    cell.follow(qs, 1.2)
    cell.gripper_to(min(world.arm.gripper_open, g.width + 0.012), 0.3, ramp_s=0.3)  # ease off, no fling
    cell.follow(cell.path(qs[-1], T_release, T_above), 0.8)
    cell.gripper_to(world.arm.gripper_open, 0.3)  # the part has settled ~1.4 s since release
    T_final = world.body_pose(part)
    pe, yaw, tilt = fixture_error(T_final, world.T_world_fixtures[part], info)
    xy = float(np.linalg.norm(T_final[:2, 3] - world.T_world_fixtures[part][:2, 3])) * 1e3
    rests = abs(T_final[2, 3] - world.table_top) * 1e3 <= REST_TOL_MM and tilt <= PLACE_TOL_DEG
    placed = pe <= PLACE_TOL_MM and yaw <= PLACE_TOL_DEG and rests
    note = (f"placed: {pe:.1f} mm (xy {xy:.1f}), yaw {yaw:.1f} deg, tilt {tilt:.1f} deg, "
            f"z {1e3 * (T_final[2, 3] - world.table_top):+.1f} mm over the table")
    return result(g.name, True, lifted, placed, pe, yaw, grip + (note if placed else "not seated: " + note[8:]))


# ---------------------------------------------------------------------------------------------- episodes

_LIBRARIES: dict[tuple, object] = {}


def _library(world: World):
    from psorr.library import ModelLibrary

    paths = tuple(str(world.catalog[n].mesh_path) for n in sorted(world.catalog))
    if paths not in _LIBRARIES:
        _LIBRARIES[paths] = ModelLibrary.from_meshes(list(paths))
    return _LIBRARIES[paths]


def recognize_poses(world: World, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """World poses (4, 4) of the parts PSORR recognises in the Kinect's cloud of ``world.data``.

    Only the best-scoring detection per model is kept; parts not returned are absent.
    """
    from psorr.kinect_noise import KINECT_V1
    from psorr.recognize import Recognizer
    from sim.sensor import DepthCamera

    with DepthCamera(world.model, world.camera_name) as camera:
        frame = camera.render(world.data, rng, KINECT_V1)
    recognition = Recognizer(_library(world)).recognize(frame.cloud, rng)
    poses, scores = {}, {}
    for det in recognition.detections:
        if det.model in world.workpieces and det.score > scores.get(det.model, -math.inf):
            poses[det.model] = np.asarray(frame.T_world_camera) @ np.asarray(det.T_cloud_model)
            scores[det.model] = det.score
    return poses


def run_episode(world: World, rng: np.random.Generator, poses: str = "oracle") -> EpisodeResult:
    """Reset the world to home and pick-and-place each workpiece once, in config order.

    ``poses="oracle"`` uses the true poses; ``"recognized"`` renders and recognises once, up front
    (the occluder at rest), and skips the parts the recognizer did not return.
    """
    if poses not in ("oracle", "recognized"):
        raise InvalidInputError(f"poses must be 'oracle' or 'recognized', got {poses!r}")
    start = time.perf_counter()
    world.reset()
    estimates = None
    if poses == "recognized":
        estimates = recognize_poses(world, rng)
    picks = []
    for part in world.workpieces:
        mujoco.mj_forward(world.model, world.data)
        if estimates is None:
            T_est = world.body_pose(part)
        elif part in estimates:
            T_est = estimates[part]
        else:
            picks.append(PickResult(part, "", False, 0.0, False, math.nan, math.nan, math.nan, math.nan,
                                    "not recognised"))
            continue
        picks.append(pick_and_place(world, part, T_est, rng))
    return EpisodeResult(tuple(picks), time.perf_counter() - start)
