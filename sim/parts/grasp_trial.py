"""Grasps tried once in MuJoCo before the cell relies on them: close, lift, shake (docs/decisions/0057).

A rest's scene: the table plane z = 0, the part as a free body with its collision hulls, mass and inertia,
and the "gripper" body of ``assets/robot/arm.xml`` (with its fingers, pads, tendon, equality and actuator)
on a free joint welded to a mocap target. The open gripper comes straight down to a grasp's tool pose
(:func:`sim.skills.grasp_planning.tool_pose`), closes as :func:`sim.skills.pick.close_on_part` does, rises
and is shaken along its three axes; the grasp holds if both pads keep the part and it slips less than limits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import trimesh

from psorr.checks import params as check
from psorr.errors import InvalidInputError
from sim.control.cell import pads_on_body
from sim.errors import SimInputError
from sim.parts.grasp import Grasp
from sim.skills.grasp_planning import LIFT, angle_deg, from_above, shift, tool_pose
from sim.world.assembly import add_part_body
from sim.world.built import pose_matrix, quat_of
from sim.world.robot import apply_arm_options, load_arm_spec

__all__ = ["GraspTrial", "GraspTrialParams", "VerifiedGrasps", "trial_grasps", "verified_grasps"]

_WELD_SOLREF = (0.01, 1.0)  # s, damping ratio of the weld pulling the gripper to its target
_CHECK_EVERY = 10  # steps between looks at the grip (20 ms)
_SHAKE_AXES = ("along closing", "across", "along the approach")  # the tool's x, y, z
_HAND = "hand/"  # the gripper's names' prefix in the scene
_PADS = (f"{_HAND}left_pad", f"{_HAND}right_pad")


@dataclass(frozen=True)
class GraspTrialParams:
    """How a grasp is tried (metres, seconds; defaults mirror :mod:`sim.skills.pick`) and what counts as held.

    Attributes:
        start_clearance: the open pads' lower ends start this far above the part's highest point, ...
        approach_speed: ... and come down at this many m/s (the pick's 0.1 m approach takes 1 s).
        settle_s: the part settles this long on the table before the first trial.
        preclose_margin, preclose_ramp_s, preclose_hold_s: the gripper closes to the grasp's width plus the
            margin, ramped, then held; then shut (``squeeze_ramp_s``, ``squeeze_hold_s``): a snap shoves the part.
        lift, lift_s: the tool rises this far in this time.
        shake_amplitude, shake_frequency, shake_cycles: then it moves out this far (A, m) and back, f times a
            second (Hz), this many times (0: none) along each of its axes: at most 2 pi^2 f^2 A m/s^2.
        slip_mm, slip_deg: the most any point of the part's hulls may move (mm) and the part turn (deg) in the
            hand (tool frame) from closing on; also on the table while settling, and while the gripper comes down.
        trials_per_rest: the best grasps of a rest tried by :func:`verified_grasps`; when none holds, the next
            are tried, one by one, up to ``max_trials_per_rest`` in all.
    """

    start_clearance: float = 0.005
    approach_speed: float = 0.1
    settle_s: float = 0.5
    preclose_margin: float = 0.006
    preclose_ramp_s: float = 0.3
    preclose_hold_s: float = 0.1
    squeeze_ramp_s: float = 0.6
    squeeze_hold_s: float = 0.4
    lift: float = LIFT
    lift_s: float = 1.0
    shake_amplitude: float = 0.03
    shake_frequency: float = 3.0
    shake_cycles: int = 2
    slip_mm: float = 10.0
    slip_deg: float = 15.0
    trials_per_rest: int = 3
    max_trials_per_rest: int = 8

    def __post_init__(self):
        try:
            check.positive(self, "approach_speed", "lift", "shake_frequency", "squeeze_ramp_s", "lift_s", "slip_mm",
                           "slip_deg")
            check.non_negative(self, "start_clearance", "preclose_margin", "shake_amplitude", "settle_s",
                               "preclose_ramp_s", "preclose_hold_s", "squeeze_hold_s")
            check.whole(self, "shake_cycles", minimum=0)
            check.whole(self, "trials_per_rest", "max_trials_per_rest")
        except InvalidInputError as exc:  # the sim's inputs raise the sim's error (still an InvalidInputError)
            raise SimInputError(str(exc)) from None
        if self.max_trials_per_rest < self.trials_per_rest:
            raise SimInputError(f"GraspTrialParams.max_trials_per_rest ({self.max_trials_per_rest}) must be at "
                                f"least trials_per_rest ({self.trials_per_rest})")


@dataclass(frozen=True)
class GraspTrial:
    """How one grasp fared: whether it ``held`` (both pads on the part from closing to the end, slipping less
    than the limits), the most a point of the part moved (``slip_mm``) and it turned (``slip_deg``) in the hand
    from closing to the trial's end (on the table, if shoved on the way down; None: never closed on it), and
    ``why`` it failed ("" if it held)."""

    grasp: str
    held: bool
    slip_mm: float | None
    slip_deg: float | None
    why: str = ""


@dataclass(frozen=True)
class VerifiedGrasps:
    """A rest's grasps after their trials: ``grasps`` (those that held, then those not tried, best first; empty
    when none tried held) and ``trials`` (in the order tried)."""

    grasps: tuple[Grasp, ...]
    trials: tuple[GraspTrial, ...]


def verified_grasps(mesh: trimesh.Trimesh, hull_files, mass: float, grasps, T_table_model=None,
                    params: GraspTrialParams = GraspTrialParams()) -> VerifiedGrasps:
    """A rest's grasps that hold in MuJoCo, then those not tried, and the trials: the best
    ``params.trials_per_rest`` are tried; when none holds, the next, one at a time, until one does or
    ``params.max_trials_per_rest`` were. The same inputs give the same numbers.

    Args:
        mesh: the part in its model frame (metres), for its centre of mass and inertia.
        hull_files: STL files of its convex collision hulls, model frame, metres.
        mass: kg.
        grasps: :class:`~sim.parts.grasp.Grasp` s in the model frame, best first, from above in this rest.
        T_table_model: (4, 4) the rest: model frame -> table frame, the part touching z = 0 (None: the
            identity, the part resting upright in its model frame as a catalog part does).
        params: how the grasps are tried.
    """
    scene, grasps = _Scene(mesh, hull_files, mass, T_table_model, params), tuple(grasps)
    trials = [_trial(scene, g) for g in grasps[: params.trials_per_rest]]
    cap = 0 if scene.settling else min(len(grasps), params.max_trials_per_rest)  # unsettled: every trial fails
    while not any(t.held for t in trials) and len(trials) < cap:
        trials.append(_trial(scene, grasps[len(trials)]))
    held = [g for g, t in zip(grasps, trials) if t.held]
    return VerifiedGrasps((*held, *grasps[len(trials):]) if held else (), tuple(trials))


def trial_grasps(mesh: trimesh.Trimesh, hull_files, mass: float, grasps, T_table_model=None,
                 params: GraspTrialParams = GraspTrialParams()) -> tuple[GraspTrial, ...]:
    """Each of ``grasps`` tried once, in order (arguments as :func:`verified_grasps`)."""
    scene = _Scene(mesh, hull_files, mass, T_table_model, params)
    return tuple(_trial(scene, g) for g in grasps)


class _Scene:
    """A rest's compiled scene (``model``, ``data``) and the state (``settled``, qpos) each trial starts from:
    the part settled at ``T_world_part`` (4, 4; its model frame), its highest point ``top`` (m), its hulls'
    outermost ``points`` (P, 3; model frame) and how far it moved ``settling`` ("" if within the slip limits);
    the gripper's full opening ``widest`` (m) and tool site in its frame, ``T_gripper_tool`` (4, 4)."""

    def __init__(self, mesh, hull_files, mass, T_table_model, params: GraspTrialParams):
        if not isinstance(mesh, trimesh.Trimesh) or not mesh.volume > 0:
            raise SimInputError("the grasp trial needs the part's closed trimesh.Trimesh, for its mass properties")
        if isinstance(mass, bool) or not isinstance(mass, (int, float)) or not math.isfinite(mass) or mass <= 0:
            raise SimInputError(f"mass must be a positive number of kg, got {mass!r}")
        missing = [str(f) for f in hull_files if not Path(f).is_file()] if len(hull_files) else ["none given"]
        if missing:
            raise SimInputError(f"the part's collision hull files are missing ({', '.join(missing)}): derive them "
                                "with sim.parts.collision.collision_hulls")
        T = np.eye(4) if T_table_model is None else np.array(T_table_model, dtype=float)
        hulls = np.concatenate([trimesh.load_mesh(str(f)).vertices for f in hull_files])
        T[2, 3] -= trimesh.transform_points(hulls, T)[:, 2].min()  # the hulls, not the mesh, rest on the table
        self.params, self.model = params, _spec(mesh, hull_files, mass, T).compile()
        self.data, self.points = mujoco.MjData(self.model), trimesh.convex.convex_hull(hulls).vertices
        self.widest = float(self.model.actuator(f"{_HAND}gripper").ctrlrange[1])  # the command opening it fully
        T_world_gripper = pose_matrix([0, 0, 1], np.eye(3))  # out of the way while the part settles
        self.start(self.model.qpos0, T_world_gripper)
        self.T_gripper_tool = np.linalg.inv(T_world_gripper) @ _pose(self.data.site(f"{_HAND}tool"))
        mujoco.mj_step(self.model, self.data, nstep=max(1, round(params.settle_s / self.model.opt.timestep)))
        self.settled, self.T_world_part = self.data.qpos.copy(), _pose(self.data.body("part"))
        mm, deg = _moved(T, self.T_world_part, self.points)
        self.settling = f"{mm:.1f} mm, {deg:.1f} deg" if mm > params.slip_mm or deg > params.slip_deg else ""
        self.top = float(trimesh.transform_points(hulls, self.T_world_part)[:, 2].max())
        self.T_tool_part, self.slip_mm, self.slip_deg = np.eye(4), 0.0, 0.0

    def start(self, qpos: np.ndarray, T_world_gripper: np.ndarray) -> None:
        """Reset to ``qpos``, at rest, with the gripper and its target at ``T_world_gripper``, fully open."""
        model, data = self.model, self.data
        mujoco.mj_resetData(model, data)
        data.qpos[:] = qpos
        adr, quat = model.joint(f"{_HAND}free").qposadr[0], quat_of(T_world_gripper[:3, :3])
        data.qpos[adr:adr + 7] = [*T_world_gripper[:3, 3], *quat]
        fingers = [model.joint(f"{_HAND}{side}_finger_joint").qposadr[0] for side in ("left", "right")]
        data.qpos[fingers] = self.widest / 2
        data.mocap_pos[0], data.mocap_quat[0] = T_world_gripper[:3, 3], quat
        data.ctrl[model.actuator(f"{_HAND}gripper").id] = self.widest
        mujoco.mj_forward(model, data)

    def move(self, T_grasp: np.ndarray, start, end, seconds: float, phase: str = "",
             profile=lambda s: 0.5 - 0.5 * math.cos(math.pi * s), opening: float | None = None) -> str:
        """Step for ``seconds``, the target moving from ``T_grasp`` (4, 4) shifted by ``start`` to it shifted by
        ``end`` (3,; world, m) along ``profile`` of the share of time gone (default: smooth), the gripper's command
        ramped to ``opening`` (m; None: kept); in a ``phase``, the grasp is watched. Why it failed, or ""."""
        model, data = self.model, self.data
        grip = model.actuator(f"{_HAND}gripper").id
        begin, steps = float(data.ctrl[grip]), round(seconds / model.opt.timestep)
        for i in range(1, steps + 1):
            data.mocap_pos[0] = T_grasp[:3, 3] + start + (end - start) * profile(i / steps)
            if opening is not None:
                data.ctrl[grip] = begin + i / steps * (opening - begin)
            mujoco.mj_step(model, data)
            failure = self.failure(phase) if phase and (i % _CHECK_EVERY == 0 or i == steps) else ""
            if failure:
                return failure
        return ""

    def in_hand(self) -> np.ndarray:
        """(4, 4) the part's pose in the tool frame now."""
        return np.linalg.inv(_pose(self.data.site(f"{_HAND}tool"))) @ _pose(self.data.body("part"))

    def pads_touching(self) -> int:
        """How many of the two pads touch the part now."""
        pads = [self.model.geom(pad).id for pad in _PADS]
        return pads_on_body(self.model, self.data, pads, self.model.body("part").id)

    def watch(self) -> None:
        """From now on, slip is measured against the part's pose in the tool frame now."""
        self.T_tool_part, self.slip_mm, self.slip_deg = self.in_hand(), 0.0, 0.0

    def failure(self, phase: str) -> str:
        """Why the watched grasp failed by now ("" while it holds), keeping the largest slip seen."""
        mm, deg = _moved(self.T_tool_part, self.in_hand(), self.points)
        self.slip_mm, self.slip_deg = max(self.slip_mm, mm), max(self.slip_deg, deg)
        if self.pads_touching() < 2:
            return f"dropped the part while {phase}"
        if mm > self.params.slip_mm or deg > self.params.slip_deg:
            return f"let the part slip {mm:.1f} mm, {deg:.1f} deg in the hand while {phase}"
        return ""


def _spec(mesh: trimesh.Trimesh, hull_files, mass: float, T: np.ndarray) -> mujoco.MjSpec:
    """The table plane; the part, a free body (body frame = model frame) at ``T`` with its hulls, mass and inertia
    (:func:`sim.world.assembly.add_part_body`, as the cell's parts); the arm's "gripper" body (and what
    refers to it: tendon, equality, actuator, exclude) on a free joint, welded to the mocap body "target"."""
    spec = mujoco.MjSpec()
    apply_arm_options(spec)
    spec.worldbody.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05])
    body = add_part_body(spec, "part", mesh, float(mass), T[:3, 3], quat_of(T[:3, :3]))
    for k, file in enumerate(hull_files):
        spec.add_mesh(name=f"hull_{k}", file=str(file))
        body.add_geom(name=f"part_hull_{k}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"hull_{k}")
    arm = load_arm_spec()
    for key in list(arm.keys):  # the arm's keyframe is the whole arm's
        arm.delete(key)
    gripper = spec.worldbody.add_frame().attach_body(arm.body("gripper"), _HAND, "")
    gripper.pos, gripper.quat = [0, 0, 0], [1, 0, 0, 0]
    gripper.add_freejoint(name=f"{_HAND}free")
    spec.worldbody.add_body(name="target", mocap=True)
    spec.add_equality(type=mujoco.mjtEq.mjEQ_WELD, name1="target", name2=gripper.name, objtype=mujoco.mjtObj.mjOBJ_BODY,
                      data=[0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0], solref=_WELD_SOLREF)  # the target's pose, exactly
    return spec


def _trial(scene: _Scene, grasp: Grasp) -> GraspTrial:
    """Down, close, lift, shake; the first failure ends the trial."""
    if scene.settling:
        return GraspTrial(grasp.name, False, None, None, f"the part did not stay so: it moved {scene.settling}")
    params, zero, T_tool = scene.params, np.zeros(3), tool_pose(scene.T_world_part, grasp, flip=False)
    if not from_above(T_tool[:3, 2]):  # as the planner
        return GraspTrial(grasp.name, False, None, None, "is not approached from above in this rest")
    T_grasp = T_tool @ np.linalg.inv(scene.T_gripper_tool)
    reach = float(scene.model.geom_size[[scene.model.geom(p).id for p in _PADS], 2].max())  # below the tool
    down = -max(0.0, (scene.top + params.start_clearance + reach - T_tool[2, 3]) / -T_tool[2, 2]) * T_tool[:3, 2]
    scene.start(scene.settled, shift(T_grasp, down))
    scene.move(T_grasp, down, zero, float(np.linalg.norm(down)) / params.approach_speed)
    mm, deg = _moved(scene.T_world_part, _pose(scene.data.body("part")), scene.points)
    if mm > params.slip_mm or deg > params.slip_deg:
        return GraspTrial(grasp.name, False, mm, deg, f"shoved the part {mm:.1f} mm, {deg:.1f} deg on the way down")
    for opening, ramp_s, hold_s in ((min(scene.widest, grasp.width + params.preclose_margin), params.preclose_ramp_s,
                                     params.preclose_hold_s), (0.0, params.squeeze_ramp_s, params.squeeze_hold_s)):
        scene.move(T_grasp, zero, zero, ramp_s, opening=opening)
        scene.move(T_grasp, zero, zero, hold_s)
    touching = scene.pads_touching()
    if touching < 2:
        return GraspTrial(grasp.name, False, None, None, "closed on air" if not touching else "one pad closed on air")
    scene.watch()
    up, cycles = np.array([0.0, 0.0, params.lift]), params.shake_cycles
    failure = scene.move(T_grasp, zero, up, params.lift_s, "lifting")
    for axis, name in enumerate(_SHAKE_AXES):
        failure = failure or scene.move(T_grasp, up, up + params.shake_amplitude * T_tool[:3, axis],
                                        cycles / params.shake_frequency, f"shaking {name}",
                                        lambda s: math.sin(math.pi * s * cycles) ** 2)
    return GraspTrial(grasp.name, not failure, scene.slip_mm, scene.slip_deg, failure)


def _moved(T_before: np.ndarray, T_after: np.ndarray, points: np.ndarray) -> tuple[float, float]:
    """(mm, deg): how far the farthest moved of the part's ``points`` (P, 3; model frame) went, and how far the
    part turned, from pose ``T_before`` to ``T_after`` (4, 4)."""
    offset = points @ (T_after[:3, :3] - T_before[:3, :3]).T + T_after[:3, 3] - T_before[:3, 3]
    return float(np.linalg.norm(offset, axis=1).max()) * 1e3, angle_deg(T_before[:3, :3].T @ T_after[:3, :3])


def _pose(element) -> np.ndarray:
    """(4, 4) world pose of a body or site of ``MjData``."""
    return pose_matrix(element.xpos, element.xmat.reshape(3, 3))
