"""Recordings of an episode for the Rerun viewer (``rerun-sdk``, the ``psorr[viz]`` extra), on a simulated-time
timeline: ``psorr-sim run TASK --rerun OUT.rrd``.

Entity paths, under ``cell``:

===========================================  ========================================================
``bodies/<body>/<geom>``                     each body's visual geoms as meshes, in the body's frame (static)
``bodies/<body>``                            the pose of each body that moves, every logged step
``looks/cloud``                              each look's depth cloud in the world frame (every second pixel)
``looks/detections/<k>_<model>``             each look's detections: the model's mesh at the pose, its score
``looks/person``                             a look the person was in the way of
``camera/recognition/...``                   each look's recognition, stage by stage, in the camera's frame
                                             (:class:`psorr.viz.RerunLogger`'s entities, the cloud aside)
``grasp_plans/<part>``                       each grasp plan's tool poses: the grasp and the seat, as axes
``protective_stops``                         each time the monitor held the arm
``picks``                                    each pick's outcome, and ``grasp_success``, a running rate
===========================================  ========================================================

Body poses are logged ``fps`` times a simulated second (default 20), on the ``sim_time`` timeline.
"""

from __future__ import annotations

import sys

import mujoco
import numpy as np

from psorr.viz.rerun_import import RerunStream
from sim.control.recorder_hooks import Recorder
from sim.world import World

VISUAL_GROUPS = (0, 1, 2)  # the cell's visual geoms; group 3 holds the collision hulls
CLOUD_STRIDE = 2  # every this many pixels of a look's depth image, across and down


class RerunEpisodeRecorder(Recorder, RerunStream):
    """Records one episode for Rerun; hand it to :class:`sim.episode.Episode` as its ``recorder``.

    Args:
        path: the ``.rrd`` file to write, or None to stream to a viewer spawned here.
        fps: body poses logged a simulated second.
        recording: log into this ``rerun.RecordingStream`` instead (its file or viewer are then the caller's).

    Attributes:
        steps: how many times the bodies' poses were logged.
    """

    def __init__(self, path=None, fps: float = 20.0, recording=None):
        from sim.errors import SimInputError

        if not fps > 0:
            raise SimInputError(f"fps must be > 0, got {fps}; the default is 20")
        RerunStream.__init__(self, "psorr-sim", path, recording)
        self.fps, self.steps = float(fps), 0
        self._next_s, self._moving, self._picks, self._grasped = 0.0, None, 0, 0
        self._recognition = None

    def _at(self, data: mujoco.MjData) -> None:
        self.recording.set_time("sim_time", duration=float(data.time))

    # ------------------------------------------------------------------------------------ Recorder protocol

    def recognition_observer(self):
        """A RerunLogger of each look's recognition into this recording, under ``cell/camera/recognition``."""
        if self._recognition is None:
            from psorr.viz.rerun_log import RerunLogger

            self._recognition = RerunLogger(recording=self.recording, prefix="cell/camera/recognition",
                                            log_cloud=False)
        return self._recognition

    def tick(self, world: World, data: mujoco.MjData) -> None:
        if self._moving is None:
            self._moving = _moving_bodies(world.model)
            self._log_geometry(world, data)
        if data.time + 1e-9 < self._next_s:
            return
        self._next_s = (np.floor(data.time * self.fps + 1e-6) + 1) / self.fps
        self._at(data)
        model = world.model
        for body in self._moving:
            self.recording.log(f"cell/bodies/{model.body(body).name}",
                               self.rr.Transform3D(translation=data.xpos[body], mat3x3=data.xmat[body].reshape(3, 3)))
        self.steps += 1

    def looked(self, world: World, data: mujoco.MjData, look, library) -> None:
        self._at(data)
        rr = self.rr
        if look.occupied:
            self.recording.log("cell/looks/person", rr.TextLog("look: the person is in view, waiting", level="INFO"))
            return
        if look.frame is not None:
            T = look.frame.T_world_camera
            points = look.frame.cloud.points.reshape(*look.frame.depth.shape, 3)[::CLOUD_STRIDE, ::CLOUD_STRIDE]
            points = points.reshape(-1, 3)
            points = points[np.isfinite(points).all(axis=1)] @ T[:3, :3].T + T[:3, 3]
            self.recording.log("cell/looks/cloud", rr.Points3D(points, colors=(150, 170, 200), radii=0.0015))
        self.recording.log("cell/looks/detections", rr.Clear(recursive=True))
        if library is None:
            return
        for k, d in enumerate(look.detections):
            model = library.model(d.model)
            T = look.frame.T_world_camera @ d.T_cloud_model
            self.recording.log(f"cell/looks/detections/{k}_{d.model}",
                               rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]),
                               rr.Mesh3D(vertex_positions=model.vertices, triangle_indices=model.faces,
                                         albedo_factor=(60, 200, 90, 160)),
                               rr.AnyValues(score=float(d.score)))

    def planned(self, world: World, data: mujoco.MjData, part: str, plan) -> None:
        self._at(data)
        poses = {"grasp": plan.T_grasp, "seat": plan.place.T_place}
        for name, T in poses.items():
            self.recording.log(f"cell/grasp_plans/{part}/{name}", self.rr.Transform3D(
                translation=T[:3, 3], mat3x3=T[:3, :3]), self.rr.TransformAxes3D(0.05))
        self.recording.log(f"cell/grasp_plans/{part}", self.rr.TextLog(f"{part}: grasp {plan.grasp.name} planned"))

    def stopped(self, world: World, data: mujoco.MjData) -> None:
        self._at(data)
        self.recording.log("cell/protective_stops", self.rr.TextLog("protective stop: someone reaches over the table",
                                                                    level="WARN"))

    def grasped(self, world: World, data: mujoco.MjData, part: str) -> None:
        self._at(data)
        self.recording.log("cell/picks", self.rr.TextLog(f"{part}: the gripper closed on it"))

    def picked(self, world: World, data: mujoco.MjData, result) -> None:
        self._at(data)
        self._picks += 1
        self._grasped += bool(result.grasped)
        outcome = "placed" if result.placed else "grasped, not placed" if result.grasped else "not grasped"
        self.recording.log("cell/picks", self.rr.TextLog(f"{result.part}: {outcome} ({result.note})",
                                                         level="INFO" if result.placed else "WARN"))
        self.recording.log("cell/picks/grasp_success", self.rr.Scalars(self._grasped / self._picks))

    # ------------------------------------------------------------------------------------ the bodies' shapes

    def _log_geometry(self, world: World, data: mujoco.MjData) -> None:
        """Every visual geom as a mesh in its body's frame, static; the bodies that never move at their pose."""
        model = world.model
        for geom in range(model.ngeom):
            if model.geom_group[geom] not in VISUAL_GROUPS:
                continue
            mesh = _geom_mesh(model, geom)
            if mesh is None:
                continue
            body = model.body(int(model.geom_bodyid[geom])).name
            vertices, faces = mesh
            rgba = model.mat_rgba[model.geom_matid[geom]] if model.geom_matid[geom] >= 0 else model.geom_rgba[geom]
            self.recording.log(f"cell/bodies/{body}/{(model.geom(geom).name or str(geom)).replace('/', '_')}",
                               self.rr.Mesh3D(vertex_positions=vertices, triangle_indices=faces,
                                              albedo_factor=np.round(np.asarray(rgba) * 255).astype(np.uint8)),
                               static=True)
        T = world.T_world_camera  # the recognizer's stages are in the camera's frame
        self.recording.log("cell/camera", self.rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]), static=True)
        for body in set(range(1, model.nbody)) - set(self._moving):
            self.recording.log(f"cell/bodies/{model.body(body).name}", self.rr.Transform3D(
                translation=data.xpos[body], mat3x3=data.xmat[body].reshape(3, 3)), static=True)


def recorder_for_option(path: str, episode: int | None) -> RerunEpisodeRecorder:
    """The recorder of ``psorr-sim run --rerun [OUT.rrd]`` for one episode: a viewer spawned now without a file,
    else ``OUT.rrd``, or ``OUT_<episode>.rrd`` when ``episode`` is given (a run of several)."""
    from psorr.cli import rerun_target

    out = rerun_target(path)
    if out is None:
        return RerunEpisodeRecorder(None)
    if episode is not None:
        out = out.with_name(f"{out.stem}_{episode}.rrd")
    print(f"recording to {out}", file=sys.stderr, flush=True)
    return RerunEpisodeRecorder(out)


def _moving_bodies(model: mujoco.MjModel) -> list[int]:
    """Bodies that move: on a joint chain (not welded to the world) or moved by mocap (the person)."""
    return [b for b in range(1, model.nbody) if model.body_weldid[b] != 0 or model.body_mocapid[b] >= 0]


def _geom_mesh(model: mujoco.MjModel, geom: int) -> tuple[np.ndarray, np.ndarray] | None:
    """(vertices (V, 3), faces (F, 3)) of a geom in its body's frame, or None for a plane (the floor)."""
    import trimesh

    kind, size = mujoco.mjtGeom(int(model.geom_type[geom])), model.geom_size[geom]
    g = mujoco.mjtGeom
    if kind == g.mjGEOM_MESH:
        m = model.geom_dataid[geom]
        v0, nv, f0, nf = model.mesh_vertadr[m], model.mesh_vertnum[m], model.mesh_faceadr[m], model.mesh_facenum[m]
        vertices, faces = model.mesh_vert[v0:v0 + nv].astype(np.float64), model.mesh_face[f0:f0 + nf]
    elif kind in (g.mjGEOM_BOX, g.mjGEOM_SPHERE, g.mjGEOM_CAPSULE, g.mjGEOM_CYLINDER, g.mjGEOM_ELLIPSOID):
        shape = {g.mjGEOM_BOX: lambda: trimesh.creation.box(extents=2 * size),
                 g.mjGEOM_SPHERE: lambda: trimesh.creation.icosphere(2, radius=size[0]),
                 g.mjGEOM_ELLIPSOID: lambda: trimesh.creation.icosphere(2, radius=1.0).apply_scale(size),
                 g.mjGEOM_CAPSULE: lambda: trimesh.creation.capsule(height=2 * size[1], radius=size[0], count=[12, 12]),
                 g.mjGEOM_CYLINDER: lambda: trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=16),
                 }[kind]()
        vertices, faces = np.asarray(shape.vertices), np.asarray(shape.faces)
    else:
        return None
    R = np.empty(9)
    mujoco.mju_quat2Mat(R, model.geom_quat[geom])
    return vertices @ R.reshape(3, 3).T + model.geom_pos[geom], faces
