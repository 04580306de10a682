"""Differential inverse kinematics of the arm's tool site, with mink and the daqp QP solver.

Each iteration solves one QP for a joint step: reach the tool pose (``FrameTask``), prefer the
home posture (a low-cost ``PostureTask`` that regularises near singularities and breaks ties),
within joint limits, joint speed limits and, when asked, a minimum distance between geom
groups. Only the six arm joints move: fingers and any other joints of a scene (free workpieces)
are frozen by equality constraints, so the arm can be solved inside a full cell model.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mink
import mujoco
import numpy as np

from sim.errors import SimInputError, UnreachableTargetError
from sim.world.robot import ArmConfig

if TYPE_CHECKING:
    from sim.world.built import World

CollisionPairs = Sequence[tuple[Sequence[str], Sequence[str]]]
"""Pairs (geom names A, geom names B): every geom of A keeps clear of every geom of B."""


@dataclass(frozen=True)
class IKResult:
    """Outcome of :meth:`ArmIK.solve`.

    Attributes:
        q: Joint configuration (nq,) of the whole model, read-only; only arm joints differ from
            ``q_start``.
        converged: Both errors are within tolerance.
        pos_error: Distance between the tool site and the target position (m).
        rot_error: Angle of the rotation from the tool frame to the target frame (rad).
        iterations: QP steps taken.
    """

    q: np.ndarray
    converged: bool
    pos_error: float
    rot_error: float
    iterations: int


def T_world_site(model: mujoco.MjModel, data: mujoco.MjData, site_name: str) -> np.ndarray:
    """Pose (4, 4) of a site in the world frame (m), from ``data`` as it is.

    The site's kinematics must be current: call ``mujoco.mj_kinematics`` (or ``mj_forward``,
    ``mj_step``) after changing ``data.qpos``.
    """
    site = model.site(site_name)
    T = np.eye(4)
    T[:3, :3] = data.site_xmat[site.id].reshape(3, 3)
    T[:3, 3] = data.site_xpos[site.id]
    return T


def pose_errors(T_world_a: np.ndarray, T_world_b: np.ndarray) -> tuple[float, float]:
    """Position (m) and rotation (rad) distance between two (4, 4) poses."""
    pos_error = float(np.linalg.norm(T_world_a[:3, 3] - T_world_b[:3, 3]))
    R_a_b = T_world_a[:3, :3].T @ T_world_b[:3, :3]
    cos_angle = np.clip((np.trace(R_a_b) - 1.0) / 2.0, -1.0, 1.0)
    return pos_error, float(np.arccos(cos_angle))


class ArmIK:
    """Iterative IK for the tool site of the arm described by ``config`` in ``model``.

    Build one per model and reuse it: tasks, limits and scratch data are set up once, collision
    limits are cached per set of pairs. Not thread-safe: one ``solve`` at a time per instance.

    Args:
        model: A compiled model holding the arm (alone, or attached in a scene).
        config: The arm's names in that model (``ArmConfig().with_prefix(...)`` after attaching).
        posture_cost: Weight of the home-posture preference, relative to 1 for the tool pose
            (1/m and 1/rad). Small, so it never holds the tool off its target.
        max_joint_speed: Joint speed limit (rad/s); the UR5e's is pi.
        step_time: Time (s) one QP step integrates over, so one step moves a joint at most
            ``max_joint_speed * step_time`` rad. Small steps keep the linearised collision
            constraints valid.
        collision_distance: Distance (m) kept between the geoms of a collision pair.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        config: ArmConfig,
        *,
        posture_cost: float = 1e-3,
        max_joint_speed: float = np.pi,
        step_time: float = 0.03,
        collision_distance: float = 0.005,
    ):
        self.model = model
        self.config = config
        self.step_time = step_time
        self.collision_distance = collision_distance
        for name in (*config.arm_joints, config.tool_site):
            kind = mujoco.mjtObj.mjOBJ_SITE if name == config.tool_site else mujoco.mjtObj.mjOBJ_JOINT
            if mujoco.mj_name2id(model, kind, name) < 0:
                raise SimInputError(f"the model has no {kind.name[6:].lower()} {name!r}: check ArmConfig's prefix")
        joints = [model.joint(name) for name in config.arm_joints]
        self._arm_qpos = np.array([int(j.qposadr[0]) for j in joints])
        arm_dofs = {int(j.dofadr[0]) for j in joints}
        frozen = [i for i in range(model.nv) if i not in arm_dofs]

        self.frame_task = mink.FrameTask(
            config.tool_site, "site", position_cost=1.0, orientation_cost=1.0, lm_damping=1.0
        )
        self.posture_task = mink.PostureTask(model, cost=posture_cost)
        self._tasks = [self.frame_task, self.posture_task]
        self._constraints = [mink.DofFreezingTask(model, dof_indices=frozen)] if frozen else None
        self._limits = [
            mink.ConfigurationLimit(model),
            mink.VelocityLimit(model, {name: max_joint_speed for name in config.arm_joints}),
        ]
        self._collision_limits: dict[tuple, mink.CollisionAvoidanceLimit] = {}
        self._configuration = mink.Configuration(model)  # reused scratch data: one solve at a time

        key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, config.home_key)
        # Without the home keyframe (e.g. a scene that dropped it) the posture is the start.
        self._home = model.key_qpos[key][self._arm_qpos].copy() if key >= 0 else None

    def solve(
        self,
        q_start: np.ndarray,
        T_world_tool_target: np.ndarray,
        collision_geoms: CollisionPairs | None = None,
        max_iters: int = 300,
        obstacles: mujoco.MjData | None = None,
        tol_pos: float = 1e-3,
        tol_rot: float = float(np.deg2rad(0.5)),
        raise_on_failure: bool = True,
    ) -> IKResult:
        """Find joints that put the tool site at ``T_world_tool_target``.

        Args:
            q_start: Configuration (nq,) to start from; non-arm entries are kept as they are.
            T_world_tool_target: Target pose (4, 4) of the tool site in the world frame (m).
            collision_geoms: Pairs (geom names A, geom names B) to keep ``collision_distance``
                apart along the way, or None. Pairs must start apart; the limit only stops them
                approaching.
            max_iters: Most QP steps before giving up.
            obstacles: Data whose mocap bodies (e.g. the moving human) are posed where they are
                now; the collision pairs see them there. None keeps the model's mocap poses.
            tol_pos: Position tolerance (m).
            tol_rot: Orientation tolerance (rad).
            raise_on_failure: Raise when not converged; otherwise return the closest attempt
                with ``converged=False``.

        Raises:
            SimInputError: Bad shapes or a target that is not a rigid transform.
            UnreachableTargetError: Not converged after ``max_iters``, or no progress for a
                long stretch (the target is out of reach or blocked).
        """
        q_start = np.asarray(q_start, dtype=float)
        T_target = np.asarray(T_world_tool_target, dtype=float)
        if q_start.shape != (self.model.nq,):
            raise SimInputError(f"q_start has shape {q_start.shape}; expected ({self.model.nq},)")
        if T_target.shape != (4, 4) or not np.all(np.isfinite(T_target)):
            raise SimInputError(f"T_world_tool_target must be a finite (4, 4) pose, got shape {T_target.shape}")
        R = T_target[:3, :3]
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise SimInputError("T_world_tool_target's rotation is not orthonormal and right-handed")

        configuration = self._configuration
        if obstacles is not None and self.model.nmocap:
            configuration.data.mocap_pos[:] = obstacles.mocap_pos
            configuration.data.mocap_quat[:] = obstacles.mocap_quat
        configuration.update(q_start.copy())
        self.frame_task.set_target(mink.SE3.from_matrix(T_target))
        posture = q_start.copy()
        if self._home is not None:
            posture[self._arm_qpos] = self._home
        self.posture_task.set_target(posture)
        limits = list(self._limits)
        if collision_geoms:
            limits.append(self._collision_limit(collision_geoms))

        def errors() -> tuple[float, float]:
            return pose_errors(T_world_site(self.model, configuration.data, self.config.tool_site), T_target)

        pos_error, rot_error = errors()
        stuck = ""
        best = (pos_error, rot_error, configuration.q)
        since_progress = 0
        iterations = 0
        step = np.inf
        # Within tolerance the loop still polishes until the steps die out (they do within a step
        # or two, the convergence being quadratic), so results are not left just under the bound.
        while iterations < max_iters and not (pos_error <= tol_pos and rot_error <= tol_rot and step < 1e-4):
            try:
                velocity = mink.solve_ik(
                    configuration,
                    self._tasks,
                    self.step_time,
                    "daqp",
                    damping=1e-6,
                    limits=limits,
                    constraints=self._constraints,
                )
            except mink.NoSolutionFound:
                # Infeasible limits, e.g. a collision pair that started closer than allowed.
                stuck = "the QP became infeasible (a collision pair starting too close?); "
                break
            configuration.integrate_inplace(velocity, self.step_time)
            step = float(np.abs(velocity).max()) * self.step_time
            iterations += 1
            pos_error, rot_error = errors()
            # Progress in either error resets the patience; the scale makes 1 mm ~ 10 mrad.
            if pos_error + 0.1 * rot_error < best[0] + 0.1 * best[1] - 1e-5:
                best = (pos_error, rot_error, configuration.q)
                since_progress = 0
            else:
                since_progress += 1
                if since_progress >= 40:
                    break

        if pos_error + 0.1 * rot_error > best[0] + 0.1 * best[1]:
            pos_error, rot_error, q = best
        else:
            q = configuration.q
        # Frozen dofs drift by round-off only; restore them so callers can rely on equality.
        keep = np.ones(self.model.nq, dtype=bool)
        keep[self._arm_qpos] = False
        q[keep] = q_start[keep]
        converged = bool(pos_error <= tol_pos and rot_error <= tol_rot)
        q.setflags(write=False)
        result = IKResult(q, converged, pos_error, rot_error, iterations)
        if not converged and raise_on_failure:
            p = ", ".join(f"{v:.3f}" for v in T_target[:3, 3])
            raise UnreachableTargetError(
                f"tool target ({p}) m is unreachable: {stuck}after {iterations} IK steps the tool is still "
                f"{pos_error * 1000:.1f} mm and {np.rad2deg(rot_error):.2f} deg away "
                f"(tolerance {tol_pos * 1000:.1f} mm, {np.rad2deg(tol_rot):.2f} deg)",
                result,
            )
        return result

    def _collision_limit(self, pairs: CollisionPairs) -> mink.CollisionAvoidanceLimit:
        key = tuple((tuple(a), tuple(b)) for a, b in pairs)
        if key not in self._collision_limits:
            unknown = [g for group in key for names in group for g in names if self._no_geom(g)]
            if unknown:
                raise SimInputError(f"collision_geoms names geoms the model does not have: {unknown}")
            # mink drops pairs that could not touch by contype/conaffinity; a named geom that collides with
            # nothing (e.g. the human occluder's "human/..." capsules) is still to be kept clear of, so it
            # counts as colliding while the pairs are listed. Distances do not depend on these bits.
            model, named = self.model, {g for group in key for names in group for g in names}
            ids = [i for i in (model.geom(g).id for g in named)
                   if model.geom_contype[i] == 0 and model.geom_conaffinity[i] == 0]
            try:
                model.geom_contype[ids], model.geom_conaffinity[ids] = 1, 1
                self._collision_limits[key] = mink.CollisionAvoidanceLimit(
                    model,
                    geom_pairs=[(list(a), list(b)) for a, b in key],
                    minimum_distance_from_collisions=self.collision_distance,
                    # Look further ahead than one step can move a geom, so no pair is skipped over.
                    collision_detection_distance=0.05,
                )
            finally:
                model.geom_contype[ids], model.geom_conaffinity[ids] = 0, 0
        return self._collision_limits[key]

    def _no_geom(self, name: str) -> bool:
        return mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, name) < 0


_IK_CACHE: dict[int, ArmIK] = {}


def ik_for(world: World) -> ArmIK:
    """One :class:`ArmIK` per compiled model, reused (building one costs ~100 ms)."""
    key = id(world.model)
    if key not in _IK_CACHE:
        _IK_CACHE.clear()
        _IK_CACHE[key] = ArmIK(world.model, world.arm)
    return _IK_CACHE[key]
