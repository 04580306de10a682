"""The cell's sensors and their rendering: the simulated Kinect v1 (:mod:`~sim.devices.sensor`, MuJoCo's
render plus psorr's noise model) and the headless OpenGL backend it renders with
(:mod:`~sim.devices.render_backend`)."""

from sim.devices.render_backend import ensure_headless_gl
from sim.devices.sensor import KINECT_V1_CAMERA, DepthCamera, SensorFrame, T_world_camera_opencv

__all__ = ["KINECT_V1_CAMERA", "DepthCamera", "SensorFrame", "T_world_camera_opencv", "ensure_headless_gl"]
