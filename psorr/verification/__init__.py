"""Verification: judging a pose against the scene.

- :mod:`~psorr.verification.scene_view`: :class:`SceneView`, the cloud as a depth buffer seen from its
  sensor, with the supporting plane and a downsampled copy for ICP;
- :mod:`~psorr.verification.box_score`: the cheap check of the paper's section 2.1.4, model and scene
  primitive boxes intersected;
- :mod:`~psorr.verification.point_check`: the point-level check of a pose against the depth buffer;
- :mod:`~psorr.verification.depth_compare`: render and compare, for the features a model lacks;
- :mod:`~psorr.verification.lateral_jitter`: a measured pixel's likelihood over the neighbours the sensor's
  lateral jitter may have read it from, for render and compare.
"""

from psorr.verification.point_check import CheckParams, PoseCheck, check_pose, check_poses
from psorr.verification.scene_view import SceneView

__all__ = ["CheckParams", "PoseCheck", "SceneView", "check_pose", "check_poses"]
