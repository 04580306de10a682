"""The simulated Kinect (sim/devices/sensor.py) on a scene of its own: what its depth means. Headless."""

import mujoco
import numpy as np

from psorr.sensing.camera import CameraIntrinsics
from sim.devices.sensor import DepthCamera, fovy_deg


def test_depth_is_z_depth_on_a_fronto_parallel_plane():
    intrinsics = CameraIntrinsics()
    model = mujoco.MjModel.from_xml_string(f"""
        <mujoco><worldbody>
          <camera name="cam" pos="0 0 1" fovy="{fovy_deg(intrinsics)}"/>
          <geom type="box" size="3 3 0.01" pos="0 0 0.19"/>
        </worldbody></mujoco>""")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    with DepthCamera(model, "cam", intrinsics) as camera:
        depth = camera.render(data).depth
    # Along the ray the corners are 0.8 / cos(38 deg) = 1.02 m away; z-depth is 0.8 everywhere.
    np.testing.assert_allclose(depth, 0.8, atol=1e-5)
