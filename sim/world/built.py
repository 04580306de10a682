"""The handle to a built cell: what :func:`sim.world.build_world` assembled, compiled and settled,
with the few operations every user of it needs (back to the home keyframe, a body's pose, the
occluder at a time). The scene itself is assembled only in ``sim.world.assembly``."""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType

import mujoco
import numpy as np

from sim.errors import SimInputError
from sim.people.occluder import ReachSchedule, occluder_pose
from sim.world.config import WorldConfig
from sim.world.robot import ArmConfig
from sim.world.tote import ToteLayout

HOME_KEY = "home"


@dataclass(frozen=True, eq=False)
class World:
    """A built cell. Poses are (4, 4) read-only arrays in the world frame (metres).

    Parts at rest sleep (MuJoCo's sleeping; see ``sim.world.assembly._scene``), and writing a sleeping part's ``qpos``
    does not move it: to place parts by hand, write their ``qpos`` right after :meth:`reset`, when
    every body is awake, or clear ``mujoco.mjtEnableBit.mjENBL_SLEEP`` in ``model.opt.enableflags``.

    Attributes:
        config: what was built.
        spec: the MjSpec it was compiled from (edit and ``spec.compile()`` for variants).
        model, data: the compiled model and a data at the ``"home"`` keyframe, forwarded.
        arm: the arm's names in this model (prefixed ``"arm/"``).
        workpieces: body names of the workpieces, in config order: a part's name, or ``<name>_<k>`` for the
            k-th of several instances (:func:`sim.world.parts.instance_names`).
        part_types: body name -> its part's name (the recognizer's model name).
        catalog: per body, its part's mesh, mass, colour and symmetries (a catalog entry, or one derived from a
            user's mesh).
        grasps: per body, its part's parallel-jaw grasps, best first (the catalog's, or synthesised).
        T_world_workpieces: settled pose of each workpiece's body (= model frame) at home.
        T_world_fixtures: per body placed in a fixture, the pose its model frame has when seated there.
        places: body -> ``"fixture"`` or ``"tote"``, where it is to be placed (empty without fixtures).
        tote: the tote's :class:`~sim.world.tote.ToteLayout` (its inside and slots), None without a tote.
        T_world_tote: the tote's pose (its inside's centre, on the table), None without a tote.
        T_world_camera: the camera's pose with OpenCV axes (x right, y down, z forward).
        camera_name: the camera to render (``sim.devices.sensor.DepthCamera(model, camera_name)``).
        table_top: z of the table top.
        T_world_arm_base: pose of the arm's mounting frame.
        occluder: the human's reach schedule, None without the occluder.
        occluder_geoms: names of the occluder's capsule geoms (= its mocap bodies' names), e.g.
            ``"human/hand"``; empty without the occluder.
    """

    config: WorldConfig
    spec: mujoco.MjSpec
    model: mujoco.MjModel
    data: mujoco.MjData
    arm: ArmConfig
    workpieces: tuple[str, ...]
    part_types: MappingProxyType
    catalog: MappingProxyType
    grasps: MappingProxyType
    T_world_workpieces: MappingProxyType
    T_world_fixtures: MappingProxyType
    T_world_camera: np.ndarray
    camera_name: str
    table_top: float
    T_world_arm_base: np.ndarray
    occluder: ReachSchedule | None = None
    occluder_geoms: tuple[str, ...] = ()
    places: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    tote: ToteLayout | None = None
    T_world_tote: np.ndarray | None = None

    def reset(self, data: mujoco.MjData | None = None) -> mujoco.MjData:
        """Put ``data`` (default: ``self.data``) at the home keyframe and forward it; return it."""
        data = self.data if data is None else data
        mujoco.mj_resetDataKeyframe(self.model, data, self.model.key(HOME_KEY).id)
        mujoco.mj_forward(self.model, data)
        return data

    @property
    def place_bodies(self) -> tuple[str, ...]:
        """The bodies parts are put in: each fixture (``<body>_fixture``), then the tote when there is one."""
        return tuple(f"{name}_fixture" for name in self.T_world_fixtures) + (("tote",) if self.tote is not None else ())

    def bodies_of(self, part: str) -> tuple[str, ...]:
        """The bodies of the part ``part`` (its instances), in config order; empty for a part not in the world."""
        return tuple(body for body, kind in self.part_types.items() if kind == part)

    def colour_name(self, body: str) -> str:
        """The palette name (``psorr.segment.PALETTE``) of ``body``'s true colour: simulator truth, to grade
        a pick of a part wanted in a colour, never what the robot goes by."""
        from psorr.segment.colour import colour_name

        return colour_name(self.catalog[body].color)

    def body_pose(self, name: str, data: mujoco.MjData | None = None) -> np.ndarray:
        """Pose (4, 4) of body ``name`` in ``data`` (default ``self.data``; kinematics must be current)."""
        data = self.data if data is None else data
        body_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)
        if body_id < 0:
            raise SimInputError(f"the world has no body {name!r}; workpieces are {list(self.workpieces)}")
        return pose_matrix(data.xpos[body_id], data.xmat[body_id].reshape(3, 3))

    def kinematics(self, q: np.ndarray) -> mujoco.MjData:
        """A scratch MjData at qpos ``q`` (nq,) with forward kinematics done; ``self.data`` is not touched."""
        data = mujoco.MjData(self.model)
        data.qpos[:] = q
        mujoco.mj_kinematics(self.model, data)
        return data

    def apply_occluder(self, data: mujoco.MjData | None = None, t: float = 0.0,
                       schedule: ReachSchedule | None = None, poses: dict | None = None) -> mujoco.MjData:
        """Pose the occluder for time ``t`` (s) of ``schedule`` (default: ``self.occluder``) in ``data``,
        or at ``poses`` (``{geom name: T_world_body}`` as :func:`sim.people.occluder.occluder_pose` gives) when given.

        Sets ``data.mocap_pos`` / ``mocap_quat`` (default ``self.data``); call ``mj_forward`` (or step)
        before reading poses or rendering. Returns ``data``. SimInputError without an occluder.
        """
        data = self.data if data is None else data
        schedule = self.occluder if schedule is None else schedule
        if not self.occluder_geoms or schedule is None:
            raise SimInputError("this world has no occluder: build it with WorldConfig(occluder=True)")
        poses = occluder_pose(schedule, t) if poses is None else poses
        for name, T in poses.items():
            mocap = self.model.body_mocapid[self.model.body(name).id]
            data.mocap_pos[mocap] = T[:3, 3]
            data.mocap_quat[mocap] = quat_of(T[:3, :3])
        return data


def pose_matrix(p, R) -> np.ndarray:
    """(4, 4) pose of position p (3,) and rotation R (3, 3)."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


def quat_of(R) -> np.ndarray:
    """MuJoCo's unit quaternion (w, x, y, z) of rotation R (3, 3)."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).ravel())
    return q
