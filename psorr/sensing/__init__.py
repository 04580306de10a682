"""Sensors: pinhole intrinsics and back-projection (:mod:`~psorr.sensing.camera`), the Kinect v1 depth-noise
model (:mod:`~psorr.sensing.kinect_noise`) and ray casting meshes into depth images
(:mod:`~psorr.sensing.raycast`)."""

from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, look_at
from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise, apply_kinect_noise

__all__ = ["KINECT_V1", "CameraIntrinsics", "KinectNoise", "apply_kinect_noise", "depth_to_cloud", "look_at"]
