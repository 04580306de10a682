"""The arm in the cell: stepping the simulation, ramped joint moves, tool paths and the gripper.

:class:`ArmCell` is what an episode drives. Every physics step goes through :meth:`ArmCell.step`,
which also moves the simulated human along its timeline, lets the workspace monitor stop the
arm while someone reaches over the table (a protective stop: the joint targets are held until
the workspace is clear), and hands frames to a recorder. IK solves keep the arm's geoms clear
of the human's capsules, posed where they are at the time of the solve.
"""

from __future__ import annotations

import math
from typing import Protocol

import mujoco
import numpy as np

from sim.control.ik import T_world_site, ik_for
from sim.control.recorder_hooks import Recorder
from sim.errors import UnreachableTargetError, WorkspaceBlockedError
from sim.people.human import ReachingHuman
from sim.world import World

RAMP_S = 0.8  # s a move's joint-space ramp lasts
SETTLE_S = 0.3  # s held at the goal after each move
CART_STEP = 0.03  # m between IK waypoints of a straight-line tool move
HUMAN_EVERY = 10  # physics steps between updates of the person's mocap poses (20 ms at 2 ms steps)
MONITOR_S = 0.25  # s of simulated time between workspace checks while the arm moves
LOOK_PAN = math.pi / 2  # rad the shoulder pans from home to take the arm out of the camera's view
MAX_STOP_S = 30.0  # s a protective stop may last before the episode gives up on the move
# N: a force with no physical effect that keeps a part awake (see ArmCell.keep_awake).
KEEP_AWAKE_N = 1e-200


class WorkspaceMonitor(Protocol):
    """Decides from the sensor alone whether someone is reaching over the table."""

    def occupied(self, data: mujoco.MjData, holding: str | None) -> bool: ...


class ArmCell:
    """The arm's handles in a world, and the stepping of ramped moves.

    Args:
        world: the cell; ``world.data`` is stepped in place.
        human: the person reaching over the table, or None to leave the occluder at rest.
        monitor: stops the arm while it reports the workspace occupied, or None.
        recorder: gets :meth:`Recorder.tick` after every physics step, or None.

    Attributes:
        holding: the part the gripper is believed to hold (None when open); the monitor ignores it.
        protective_stops, stopped_s: how often and how long the monitor held the arm.
        min_human_clearance: least distance (m) seen between the arm's geoms and the human's.
    """

    def __init__(self, world: World, human: ReachingHuman | None = None, monitor: WorkspaceMonitor | None = None,
                 recorder: Recorder | None = None):
        m, cfg = world.model, world.arm
        self.world, self.model, self.data, self.cfg = world, m, world.data, cfg
        self.ik = ik_for(world)
        self.act = np.array([m.actuator(a).id for a in cfg.arm_actuators])
        self.qadr = np.array([m.joint(j).qposadr[0] for j in cfg.arm_joints])
        self.gripper = m.actuator(cfg.gripper_actuator).id
        self.pads = [m.geom(g).id for g in cfg.pad_geoms]
        finger_bodies = {m.jnt_bodyid[m.joint(j).id] for j in cfg.finger_joints}
        self.finger_geoms = {g for g in range(m.ngeom) if m.geom_bodyid[g] in finger_bodies}
        # The pads are centred on the tool site along its z: they reach this far beyond it.
        self.pad_reach = float(max(m.geom_size[p][2] for p in self.pads))
        self.table = ["table_collision"]
        self.human, self.monitor, self.recorder = human, monitor, recorder
        self._human_poses = None
        self.holding: str | None = None
        self._kept_awake: str | None = None
        self.steps = 0
        self.protective_stops, self.stopped_s = 0, 0.0
        self.min_human_clearance = math.inf
        self._next_check = 0.0
        self._arm_geoms = [m.geom(g).id for g in cfg.collision_geoms]
        self._arm_base = m.body(cfg.base_body).id
        # Body ids are depth-first, so the arm's geoms in body-id order run from the base out to the hand.
        self._arm_geoms_in_chain = sorted(self._arm_geoms, key=lambda g: int(m.geom_bodyid[g]))
        self._human_geoms = [m.geom(g).id for g in world.occluder_geoms] if human is not None else []
        if human is not None:
            self._move_human()
            mujoco.mj_forward(m, self.data)

    def keep_awake(self, part: str | None) -> None:
        """Keep ``part`` from sleeping until the next call (None: let the one kept so far sleep again).

        MuJoCo lets a (nearly) still body sleep, and nothing wakes it when its support goes: a chassis
        at rest against one pad fell asleep as the gripper eased off, and hung in the air after the
        release (5 of 50 episodes). A tree with a nonzero applied force never sleeps, so the part gets
        a force of no physical effect, :data:`KEEP_AWAKE_N`.
        """
        if self._kept_awake is not None:
            self.data.xfrc_applied[self.model.body(self._kept_awake).id] = 0.0
        if part is not None:
            self.data.xfrc_applied[self.model.body(part).id, 2] = KEEP_AWAKE_N
        self._kept_awake = part

    # -------------------------------------------------------------------------------- stepping

    def _physics_step(self) -> None:
        if self.human is not None and self.steps % HUMAN_EVERY == 0:
            self._move_human()
        mujoco.mj_step(self.model, self.data)
        self.steps += 1
        if self.recorder is not None:
            self.recorder.tick(self.world, self.data)

    def _move_human(self) -> None:
        poses = self.human.update(self.data.time, self._footprint())
        if poses is not self._human_poses:
            self.world.apply_occluder(self.data, poses=poses)
            self._human_poses = poses

    def _footprint(self) -> np.ndarray:
        """(N, 2) the arm as the person sees it from above: a polyline from the base through every link's
        collision geom (both ends of a capsule or cylinder, a box's centre) to the tool. The links' body
        origins alone sit on the joint axes, and the UR5e's upper arm runs up to 0.2 m beside them: a
        person keeping 0.25 m from those reached into the stopped upper arm (2 of 50 episodes)."""
        m, d = self.model, self.data
        points = [d.xpos[self._arm_base, :2]]
        for g in self._arm_geoms_in_chain:
            if m.geom_type[g] in (mujoco.mjtGeom.mjGEOM_CAPSULE, mujoco.mjtGeom.mjGEOM_CYLINDER):
                half = m.geom_size[g, 1] * d.geom_xmat[g].reshape(3, 3)[:, 2]
                points += [(d.geom_xpos[g] - half)[:2], (d.geom_xpos[g] + half)[:2]]
            else:
                points.append(d.geom_xpos[g, :2])
        points.append(T_world_site(m, d, self.cfg.tool_site)[:2, 3])
        return np.array(points)

    def step(self, n: int, watch: bool = True) -> None:
        """Step the physics ``n`` times; while ``watch``ing, a protective stop inserts extra steps with
        the targets held."""
        for _ in range(n):
            self._physics_step()
            if watch and self.data.time >= self._next_check:
                self._next_check = self.data.time + MONITOR_S
                self._track_clearance()
                if self.monitor is not None and self.monitor.occupied(self.data, self.holding):
                    self._protective_stop()

    def hold(self, seconds: float) -> None:
        """Keep the current targets for ``seconds`` of simulated time (waiting, thinking); the arm is still,
        so the monitor need not watch."""
        self.step(max(0, round(seconds / self.model.opt.timestep)), watch=False)

    def _protective_stop(self) -> None:
        self.protective_stops += 1
        if self.recorder is not None:
            self.recorder.stopped(self.world, self.data)
        start = self.data.time
        while self.monitor.occupied(self.data, self.holding):
            if self.data.time - start > MAX_STOP_S:
                raise WorkspaceBlockedError(f"the workspace stayed occupied for {MAX_STOP_S:.0f} s")
            for _ in range(round(MONITOR_S / self.model.opt.timestep)):
                self._physics_step()
            self._track_clearance()
        self.stopped_s += self.data.time - start
        self._next_check = self.data.time + MONITOR_S

    def _track_clearance(self) -> None:
        if not self._human_geoms:
            return
        fromto = np.zeros(6)
        for a in self._arm_geoms:
            for h in self._human_geoms:
                d = mujoco.mj_geomDistance(self.model, self.data, a, h, 0.2, fromto)
                self.min_human_clearance = min(self.min_human_clearance, d)

    # -------------------------------------------------------------------------------- planning

    def solve(self, q_start: np.ndarray, T: np.ndarray, avoid_table: bool = False) -> np.ndarray:
        """Joints (nq,) putting the tool at ``T``, clear of the human (and of the table if asked)."""
        pairs = [(self.cfg.collision_geoms, self.table)] if avoid_table else []
        if self._human_geoms:
            pairs.append((self.cfg.collision_geoms, list(self.world.occluder_geoms)))
        obstacles = self.data if self._human_geoms else None
        try:
            return np.array(self.ik.solve(q_start, T, collision_geoms=pairs or None, obstacles=obstacles).q)
        except UnreachableTargetError:  # the local solver can stall far from home: retry from home
            q_home = np.array(q_start, dtype=float)
            q_home[self.qadr] = self.model.key(self.cfg.home_key).qpos[self.qadr]
            return np.array(self.ik.solve(q_home, T, collision_geoms=pairs or None, obstacles=obstacles).q)

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

    # -------------------------------------------------------------------------------- moving

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
        return pads_on_body(self.model, self.data, self.pads, body) == len(self.pads)

    def look_pose(self) -> np.ndarray:
        """Arm joints (6,) of the pose the robot looks from: home, panned aside out of the camera's view."""
        q = self.model.key(self.cfg.home_key).qpos[self.qadr].copy()
        q[0] += LOOK_PAN
        return q

    def clear_the_view(self) -> None:
        """Swing the arm to :meth:`look_pose` unless it is (commanded) there already."""
        goal = self.look_pose()
        if not np.allclose(self.data.ctrl[self.act], goal, atol=1e-3):
            self.move_joints(goal, ramp_s=1.5)

    def commanded_q(self) -> np.ndarray:
        """qpos (nq,) with the arm's joints at their commanded targets, not where they sag to."""
        q = self.data.qpos.copy()
        q[self.qadr] = self.data.ctrl[self.act]
        return q


def pads_on_body(model: mujoco.MjModel, data: mujoco.MjData, pads, body: int) -> int:
    """How many of the geoms ``pads`` (ids) are in contact with a geom of ``body`` now."""
    pairs = data.contact.geom[: data.ncon]
    other_on_body = (model.geom_bodyid[pairs] == body)[:, ::-1]
    return sum(bool(np.any(other_on_body & (pairs == pad))) for pad in pads)
