"""A simulated Kinect v1: MuJoCo renders RGB, and depth with the body each pixel sees in one pass
(:class:`sim.devices.depth_render.DepthBodyRenderer`); psorr adds the noise.

Frames. MuJoCo's camera looks along its -z with x right and y up; psorr's clouds use OpenCV
axes (x right, y down, z forward). :func:`T_world_camera_opencv` is the one place that converts
between them; everything else (the world's ``T_world_camera``, the frames' clouds) uses it.

Depth. The renderer returns z-depth in metres: the distance along the optical axis, not
along the pixel's ray (tests/sim/devices/test_sensor.py checks it on a fronto-parallel plane). That is what
:func:`psorr.sensing.camera.depth_to_cloud` and the noise model expect.

Rendering is headless: :func:`sim.devices.render_backend.ensure_headless_gl` picks EGL or OSMesa before
the renderer is made.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud
from psorr.sensing.kinect_noise import KinectNoise, kinect_noise_with_source
from psorr.types import PointCloud
from sim.devices.depth_render import DepthBodyRenderer
from sim.devices.render_backend import ensure_headless_gl
from sim.errors import SimInputError

KINECT_V1_CAMERA = CameraIntrinsics.kinect_v1()
"""640x480, f = 525 px, centred: the default camera (fovy 2 atan(240 / 525) = 49.1 deg)."""
_MUJOCO_TO_OPENCV = np.diag([1.0, -1.0, -1.0])  # flips y (up -> down) and z (backward -> forward)


def _camera_id(model: mujoco.MjModel, camera: str | int) -> int:
    names = [model.camera(i).name for i in range(model.ncam)]
    if isinstance(camera, str):
        cam_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
    else:
        cam_id = int(camera) if 0 <= int(camera) < model.ncam else -1
    if cam_id < 0:
        raise SimInputError(f"the model has no camera {camera!r}; choose one of {names}")
    return cam_id


def T_world_camera_opencv(model: mujoco.MjModel, data: mujoco.MjData, camera: str | int) -> np.ndarray:
    """Pose (4, 4) of a MuJoCo camera in the world, with OpenCV axes (x right, y down, z forward), metres.

    The only conversion between MuJoCo's camera axes and OpenCV's in the project. ``data`` must
    hold current camera poses: ``mj_forward`` after changing ``qpos`` (``mj_kinematics`` alone does
    not place cameras; ``mj_camlight`` does).
    """
    cam_id = _camera_id(model, camera)
    T = np.eye(4)
    T[:3, :3] = data.cam_xmat[cam_id].reshape(3, 3) @ _MUJOCO_TO_OPENCV
    T[:3, 3] = data.cam_xpos[cam_id]
    return T


def fovy_deg(intrinsics: CameraIntrinsics) -> float:
    """MuJoCo's vertical field of view (degrees) for a pinhole camera: 2 atan(H / 2 / fy) (49.1 for a Kinect)."""
    return math.degrees(2.0 * math.atan(intrinsics.height / 2.0 / intrinsics.fy))


def check_intrinsics(intrinsics: CameraIntrinsics) -> None:
    """Raise SimInputError unless MuJoCo's centred square-pixel camera can render ``intrinsics``."""
    centred = (intrinsics.width - 1) / 2.0, (intrinsics.height - 1) / 2.0
    if not math.isclose(intrinsics.fx, intrinsics.fy, rel_tol=1e-9) or not np.allclose(
        (intrinsics.cx, intrinsics.cy), centred
    ):
        raise SimInputError(
            f"MuJoCo renders a pinhole camera with square pixels and a centred principal point: need fx == fy "
            f"and (cx, cy) = {centred}, got fx={intrinsics.fx}, fy={intrinsics.fy}, "
            f"(cx, cy)=({intrinsics.cx}, {intrinsics.cy})"
        )


@dataclass(frozen=True, eq=False)
class SensorFrame:
    """One simulated Kinect frame.

    Attributes:
        cloud: organised PointCloud of H*W points (row-major, index v * W + u) in the camera's
            OpenCV frame, metres; NaN where there is no return. ``colors`` from ``rgb`` in [0, 1],
            ``labels`` the body id each point lies on (-1 where there is no return).
        rgb: (H, W, 3) uint8 colour image (noise-free), read-only; None when rendered without colour.
        depth: (H, W) float64 z-depth in metres, 0 where there is no return (noisy if noise was
            given), read-only.
        segmentation: (H, W) int64 id of the body whose geom each pixel sees, -1 for none;
            aligned with ``depth`` (it follows the noise's lateral jitter), set even where the
            noise dropped the depth. Read-only.
        T_world_camera: (4, 4) camera pose (OpenCV axes) when the frame was taken, read-only.
    """

    cloud: PointCloud
    rgb: np.ndarray | None
    depth: np.ndarray
    segmentation: np.ndarray
    T_world_camera: np.ndarray

    def __post_init__(self):
        for name in ("rgb", "depth", "segmentation", "T_world_camera"):
            if getattr(self, name) is not None:
                getattr(self, name).setflags(write=False)


class DepthCamera:
    """Renders :class:`SensorFrame` s from a camera of a MuJoCo model (one offscreen renderer, reused).

    Args:
        model: compiled model holding the camera; its offscreen buffer must be at least the image size.
        camera_name: the camera's name.
        intrinsics: the image size and focal length; must match the camera's ``fovy``
            (2 atan(H / 2 / fy)) with a centred principal point.

    Not thread-safe. Call :meth:`close` (or use it as a context manager) to free the GL context.
    """

    def __init__(self, model: mujoco.MjModel, camera_name: str, intrinsics: CameraIntrinsics = KINECT_V1_CAMERA):
        self.model = model
        self.camera_name = camera_name
        self.intrinsics = intrinsics
        self._camera_id = _camera_id(model, camera_name)
        check_intrinsics(intrinsics)
        fovy = float(model.cam_fovy[self._camera_id])
        if not math.isclose(fovy, fovy_deg(intrinsics), abs_tol=1e-3):
            raise SimInputError(
                f"camera {camera_name!r} has fovy {fovy:.4f} deg but the intrinsics need {fovy_deg(intrinsics):.4f} "
                f"(fy = {intrinsics.fy} px for {intrinsics.height} rows): set the camera's fovy or pass matching "
                f"intrinsics"
            )
        off = (model.vis.global_.offwidth, model.vis.global_.offheight)
        if off[0] < intrinsics.width or off[1] < intrinsics.height:
            raise SimInputError(
                f"the model's offscreen buffer is {off[0]}x{off[1]}, smaller than the {intrinsics.width}x"
                f"{intrinsics.height} image: raise visual/global offwidth and offheight"
            )
        ensure_headless_gl()
        self._renderer = mujoco.Renderer(model, intrinsics.height, intrinsics.width)  # colour
        self._depth = DepthBodyRenderer(model, intrinsics.height, intrinsics.width, self._camera_id)

    def render(
        self, data: mujoco.MjData, rng: np.random.Generator | None = None, noise: KinectNoise | None = None,
        rgb: bool = True,
    ) -> SensorFrame:
        """Render the camera's view of ``data`` (kinematics must be current).

        Args:
            data: the state to render.
            rng: the noise's only randomness; needed when ``noise`` is given.
            noise: the Kinect noise model to apply to the depth, or None for exact depth.
            rgb: also render the colour image (the dearest of the three passes on a CPU); without it
                the frame's ``rgb`` and the cloud's colours are None.
        """
        if noise is not None and not isinstance(rng, np.random.Generator):
            raise SimInputError("render with noise needs rng, a numpy.random.Generator")
        image = None
        if rgb:
            self._renderer.update_scene(data, camera=self._camera_id)
            image = self._renderer.render().copy()
        depth, body = self._depth.render(data)
        colors = image.reshape(-1, 3) if image is not None else None
        if noise is not None:
            depth, source = kinect_noise_with_source(depth, self.intrinsics, rng, noise)
            body = body.ravel()[source].reshape(body.shape)
            colors = colors[source.ravel()] if colors is not None else None
        cloud = depth_to_cloud(depth, self.intrinsics, colors=None if colors is None else colors / 255.0, labels=body)
        T = T_world_camera_opencv(self.model, data, self._camera_id)
        return SensorFrame(cloud=cloud, rgb=image, depth=depth, segmentation=body, T_world_camera=T)

    def close(self) -> None:
        """Free the renderer's GL context; the camera cannot render afterwards."""
        self._renderer.close()
        self._depth.close()

    def __enter__(self) -> DepthCamera:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
