"""Sensors: pinhole intrinsics and back-projection (:mod:`~psorr.sensing.camera`), the Kinect v1 depth-noise
model (:mod:`~psorr.sensing.kinect_noise`), ray casting meshes into depth images
(:mod:`~psorr.sensing.raycast`), and thinning clouds finer than the sensor model to its sampling
(:mod:`~psorr.sensing.resolution`)."""

from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, look_at
from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise, apply_kinect_noise
from psorr.sensing.resolution import ThinnedCloud, thin_to_focal

__all__ = ["KINECT_V1", "CameraIntrinsics", "KinectNoise", "ThinnedCloud", "apply_kinect_noise", "depth_to_cloud",
           "look_at", "thin_to_focal"]
