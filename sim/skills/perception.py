"""What the robot knows about the cell: the Kinect's frames, PSORR's detections, and whether someone is reaching in.

The robot sees through the camera and knows its own body, nothing else. "Someone is reaching
over the table" is decided from the depth image alone: points above the table's footprint
higher than any resting workpiece stands (plus a margin) are something that does not belong
there. Two things are filtered out first, both from the robot's knowledge of itself: its own
arm (the pixels where its model, rendered at the known joint angles, lies; that is what the
segmentation render's arm pixels are) and, while it holds one, the part in its hand (a ball
around the tool of the part's size). PSORR is also spared the fixtures' pixels: the robot knows
where the fixtures stand, since it places parts into them, and to the recognizer their walls are
part-sized things on the table that no model explains, each costing a finer second look.

The same test serves the look before a pick (the full Kinect frame) and the protective-stop
monitor while the arm moves (a 160x120 depth render every 0.25 s; see :mod:`sim.control.cell`).
"""

from __future__ import annotations

from types import MappingProxyType

import mujoco
import numpy as np

from psorr.sensing.camera import CameraIntrinsics
from psorr.types import Detection, PointCloud
from sim.control.ik import T_world_site
from sim.devices.depth_render import DepthBodyRenderer
from sim.devices.sensor import DepthCamera, SensorFrame, T_world_camera_opencv
from sim.errors import SimInputError
from sim.skills.looks import Estimate, HeldLook, Look
from sim.skills.monitor_gate import MonitorGate, noise_margin
from sim.skills.perception_params import PerceptionParams
from sim.world import World
from sim.world.parts import standing_height

CEILING_MARGIN = 0.03  # m above the tallest resting part before a point counts as an intrusion
INTRUSION_FRACTION = 0.001  # of the image's pixels: fewer intruding points than this are noise
WORKSPACE_BELOW = 0.03  # m below the table top the workspace crop starts (the table's own points stay in)
MONITOR_CAMERA = CameraIntrinsics(width=160, height=120, fx=131.25, fy=131.25, cx=79.5, cy=59.5)
MONITOR_OCCUPIED = INTRUSION_FRACTION * MONITOR_CAMERA.width * MONITOR_CAMERA.height  # intruding points
"""The monitor's depth stream: the Kinect's field of view at a quarter of its resolution."""


class Perception:
    """The robot's senses in ``world``: a Kinect for looks, a low-resolution depth monitor, PSORR.

    Args:
        world: the cell.
        rng: the sensor noise's randomness (the monitor draws its own from it).
        recognize: run PSORR on each look (False: looks only check occupancy).
        rgb: render the colour image with each look (for a recorder or a viewer; PSORR needs depth only).
        colours: name each detection's colour from the points that support it in the look's colour image (to
            pick a part by its colour); renders the colour image whatever ``rgb`` says.
        params: the recognizer method and the sensor's noise level (default: PSORR, the Kinect v1's noise).
        observer: watches each look's recognition (:class:`psorr.viz.RecognitionObserver`), or None.

    Each look after the first gives PSORR the last recognised look's detections to follow (the camera stands
    still): they are judged again where they were, and only what they no longer explain is searched, so a
    look after a pick costs what the part gone and any part it nudged cost (``psorr.acceptance.known``).

    Call :meth:`close` (or use it as a context manager) to free the renderers.
    """

    def __init__(self, world: World, rng: np.random.Generator, recognize: bool = True, rgb: bool = True,
                 colours: bool = False, params: PerceptionParams | None = None, observer=None):
        self.world, self.rng, self.rgb, self.colours = world, rng, rgb or colours, colours
        self.observer = observer
        self.params = params or PerceptionParams()
        self._noise = self.params.noise
        self.camera = DepthCamera(world.model, world.camera_name)
        self._monitor = DepthBodyRenderer(world.model, MONITOR_CAMERA.height, MONITOR_CAMERA.width,
                                          world.model.camera(world.camera_name).id)
        self._recognizer = _recognizer(world, self.params.method) if recognize else None
        self._known: tuple[Detection, ...] = ()  # the last recognised look's detections, camera frame
        model = world.model
        base = model.body(world.arm.base_body).id
        self._arm_bodies = np.array([b for b in range(model.nbody) if _descends(model, b, base)])
        places = world.place_bodies
        self._fixture_bodies = np.array([model.body(name).id for name in places], dtype=np.int64)
        self._places = [_place_volume(world, name) for name in places]
        heights = [standing_height(world.config, world.catalog[p]) for p in world.workpieces]
        self.ceiling = world.table_top + max(heights) + CEILING_MARGIN
        self._monitor_rays = MONITOR_CAMERA.pixel_rays().reshape(-1, 3)
        half_extent = tuple(v / 2 for v in world.config.table_size)
        margin = noise_margin(self._noise.depth_sigma, world.T_world_camera, half_extent, world.table_top)
        self._gate = MonitorGate(model, self._monitor.drawn_groups, self._arm_bodies, half_extent, self.ceiling,
                                 margin)

    @property
    def library(self):
        """The recognizer's :class:`psorr.library.models.ModelLibrary`, or None when not recognising."""
        return self._recognizer.library if self._recognizer is not None else None

    # -------------------------------------------------------------------------------- looking

    def look(self, data: mujoco.MjData, holding: str | None = None) -> Look:
        """Render the Kinect, count intruding points and (when nobody intrudes and recognising) run PSORR.

        PSORR gets the cloud cropped to the workspace: the table's footprint from just below its
        top up to the ceiling, less the robot's own pixels and the fixtures'. Cropped points become
        NaN, so the cloud stays organised.
        """
        frame = self.camera.render(data, self.rng, self._noise, rgb=self.rgb)
        T = frame.T_world_camera
        world_pts, valid = self._world_points(frame)
        intruding = self._count_intruding(world_pts[valid], data, holding)
        occupied = intruding >= INTRUSION_FRACTION * len(world_pts)
        detections, estimates = (), {}
        if self._recognizer is not None and not occupied:
            cloud = self._workspace_cloud(frame, world_pts, valid, self.ceiling)
            detections = tuple(self._recognizer.recognize(cloud, self.rng, known=self._known,
                                                          observer=self.observer).detections)
            self._known = detections
            for det in detections:
                if det.model in self.world.part_types.values():
                    estimates.setdefault(det.model, []).append(
                        Estimate(T @ det.T_cloud_model, det.score, tuple(T @ A for A in det.alternatives),
                                 self._colour(cloud, det)))
        estimates = {k: tuple(sorted(v, key=lambda e: -e.score)) for k, v in estimates.items()}
        return Look(frame, detections, MappingProxyType(estimates), intruding, bool(occupied))

    def _colour(self, cloud: PointCloud, detection: Detection) -> str | None:
        if not self.colours:
            return None
        from psorr.segment.support_colour import supported_colour

        colour = supported_colour(cloud, detection, self._recognizer.library.model(detection.model))
        return None if colour is None else colour.name

    def look_at_held(self, data: mujoco.MjData, part: str, T_world_part: np.ndarray) -> HeldLook:
        """Render the Kinect and refine the pose (4, 4, world) of ``part``, held up in the hand, from
        ``T_world_part`` (PSORR's :meth:`~psorr.recognize.Recognizer.refine`). The cloud is the look's
        crop without its ceiling (the part is above it) and without the arm's pixels (the fingers'
        included)."""
        if self._recognizer is None:
            raise SimInputError("look_at_held needs a Perception built with recognize=True")
        frame = self.camera.render(data, self.rng, self._noise, rgb=False)
        T = frame.T_world_camera
        world_pts, valid = self._world_points(frame)
        cloud = self._workspace_cloud(frame, world_pts, valid)
        with_arm = self._workspace_cloud(frame, world_pts, np.isfinite(frame.cloud.points[:, 2]))
        return HeldLook(self._recognizer.refine(cloud, part, np.linalg.inv(T) @ T_world_part), T, with_arm)

    def _world_points(self, frame: SensorFrame) -> tuple[np.ndarray, np.ndarray]:
        """The frame's points in the world frame (N, 3; NaN rows stay NaN), and which are measured and
        not the robot's own arm (N,)."""
        T = frame.T_world_camera
        pts = frame.cloud.points
        own = np.isin(frame.segmentation.ravel(), self._arm_bodies)
        return pts @ T[:3, :3].T + T[:3, 3], np.isfinite(pts[:, 2]) & ~own

    def _workspace_cloud(self, frame: SensorFrame, world_pts: np.ndarray, valid: np.ndarray,
                         ceiling: float = np.inf) -> PointCloud:
        """PSORR's cloud: the ``valid`` points in the workspace up to ``ceiling`` (world z, m), less the places
        (fixtures, the tote) and what stands in them: the robot knows its places, and a part it has placed is
        not one to find again. Cropped points become NaN, so the cloud stays organised."""
        with np.errstate(invalid="ignore"):
            keep = (valid & self._in_workspace(world_pts) & (world_pts[:, 2] <= ceiling)
                    & ~np.isin(frame.segmentation.ravel(), self._fixture_bodies))
            for T_body_world, lo, hi in self._places:
                xy = world_pts @ T_body_world[:2, :3].T + T_body_world[:2, 3]
                keep &= ~np.all((xy >= lo) & (xy <= hi), axis=1)
        return _masked(frame.cloud, keep)

    def _in_workspace(self, world_pts: np.ndarray) -> np.ndarray:
        hx, hy = (v / 2 for v in self.world.config.table_size)
        return ((np.abs(world_pts[:, 0]) < hx) & (np.abs(world_pts[:, 1]) < hy)
                & (world_pts[:, 2] > self.world.table_top - WORKSPACE_BELOW))

    def occupied(self, data: mujoco.MjData, holding: str | None = None) -> bool:
        """The monitor's verdict: is someone reaching over the table now? (See :meth:`monitor_intruding`.)"""
        return self.monitor_intruding(data, holding) >= MONITOR_OCCUPIED

    def monitor_intruding(self, data: mujoco.MjData, holding: str | None = None) -> int:
        """How many points of the monitor's image are above the workspace, neither a part nor the robot.

        It reads a 160x120 depth image with the Kinect's depth noise (its standard deviation at each
        depth, as the full-resolution model gives it). The model's pixel-scale effects (lateral
        jitter, edge dropouts, the shadow band) are below a pixel at this resolution and are left out:
        the full model costs more than the render, and the monitor runs four times a second.

        While nothing but the robot and its held part reaches near the ceiling, it is 0 without a render
        (:mod:`sim.skills.monitor_gate`).
        """
        if not self._gate.may_intrude(data, *self._held_ball(data, holding)):
            return 0
        depth, body = self._monitor.render(data)
        depth = np.where(np.isin(body, self._arm_bodies), 0.0, depth).ravel()
        keep = depth > 0
        # depth_sigma's disparity step is the full-resolution sensor's, which the monitor's image is binned from.
        depth[keep] += self.rng.normal(size=int(keep.sum())) * self._noise.depth_sigma(depth[keep])
        T = T_world_camera_opencv(self.world.model, data, self.world.camera_name)
        pts = (self._monitor_rays[keep] * depth[keep, None]) @ T[:3, :3].T + T[:3, 3]
        return self._count_intruding(pts, data, holding)

    def _count_intruding(self, world_pts: np.ndarray, data: mujoco.MjData, holding: str | None) -> int:
        inside = self._in_workspace(world_pts) & (world_pts[:, 2] > self.ceiling)
        if holding is not None and np.any(inside):
            _, tool, radius = self._held_ball(data, holding)
            inside &= np.linalg.norm(world_pts - tool, axis=1) > radius
        return int(np.count_nonzero(inside))

    def _held_ball(self, data: mujoco.MjData, holding: str | None) -> tuple[int | None, np.ndarray | None, float]:
        """The held part's body id, the tool's position (3,) and the radius (m) around it that the held part
        explains (its box's diagonal, plus 2 cm); (None, None, 0) when the hand is empty."""
        if holding is None:
            return None, None, 0.0
        tool = T_world_site(self.world.model, data, self.world.arm.tool_site)[:3, 3]
        radius = float(np.linalg.norm(np.ptp(self.world.catalog[holding].bounds(), axis=0))) + 0.02
        return self.world.model.body(holding).id, tool, radius

    def close(self) -> None:
        self.camera.close()
        self._monitor.close()

    def __enter__(self) -> Perception:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _place_volume(world: World, body: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A place's (fixture's or tote's) footprint: T_body_world (4, 4) and the (2,) lo, hi corners of its box
    walls in the body's frame; everything above it belongs to the place."""
    model, data = world.model, world.data
    b = model.body(body).id
    geoms = np.flatnonzero(model.geom_bodyid == b)
    corners = np.concatenate([model.geom_pos[g, :2] + np.array([[-1, -1], [1, 1]]) * model.geom_size[g, :2]
                              for g in geoms])
    T_world_body = np.eye(4)
    T_world_body[:3, :3], T_world_body[:3, 3] = data.xmat[b].reshape(3, 3), data.xpos[b]
    return np.linalg.inv(T_world_body), corners.min(axis=0), corners.max(axis=0)


def _masked(cloud: PointCloud, keep: np.ndarray) -> PointCloud:
    """``cloud`` with the points outside ``keep`` set to NaN (and label -1), still organised."""
    points = np.where(keep[:, None], cloud.points, np.nan)
    labels = None if cloud.labels is None else np.where(keep, cloud.labels, -1)
    return PointCloud(points, colors=cloud.colors, normals=None, labels=labels, width=cloud.width,
                      height=cloud.height)


def _descends(model: mujoco.MjModel, body: int, root: int) -> bool:
    while body > 0:
        if body == root:
            return True
        body = int(model.body_parentid[body])
    return False


_RECOGNIZERS: dict[tuple, object] = {}


def _recognizer(world: World, method: str):
    """A recognizer for every part in the world (trained once per process; cached on disk by psorr)."""
    from psorr.library.models import ModelLibrary
    from psorr.recognize import Recognizer

    paths = tuple(sorted({str(info.mesh_path) for info in world.catalog.values()}))  # one per part, not body
    if (paths, method) not in _RECOGNIZERS:
        _RECOGNIZERS[paths, method] = Recognizer(ModelLibrary.from_meshes(list(paths)), method=method)
    return _RECOGNIZERS[paths, method]
