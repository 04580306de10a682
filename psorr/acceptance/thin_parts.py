"""Telling a part thinner than the depth tolerance from the table it lies on.

A pose is evidence of a part only where the part explains the measurement better than the table does.
Acceptance counts the supported points that stand higher above the table than their depth tolerance
(``AcceptParams.min_support_above_table``). A plate lying flat has none: at 0.8 m a Kinect's tolerance is
about 5 mm, and a 4 mm plate's top face is within it of the table everywhere. Point by point such a plate
is table; over its whole face it is not, when its face stands at least one disparity step above the table:
finer than that, the sensor quantises plate and table to the same depth, and no averaging recovers the
difference. So a pose that cannot show enough points clear of the tolerance, and whose face stands at
least a step high, is judged by render and compare against the bare table instead.
"""

from __future__ import annotations

import numpy as np

from psorr.acceptance.render_judge import DECISIVE_SPREADS
from psorr.sensing.noise_context import depth_noise
from psorr.verification.depth_compare import RESIDUAL_CAP, DepthRenderer, table_costs
from psorr.verification.point_check import CheckParams, PoseCheck, depth_tolerance
from psorr.verification.scene_view import SceneView

# Disparity steps the pose's face must stand above the table for the sensor to tell them apart at all.
RESOLVABLE_STEPS = 1.0


def clear_of_table(view: SceneView, model, renderer: DepthRenderer, T_cloud_model: np.ndarray,
                   check: PoseCheck, need: int, params: CheckParams) -> bool:
    """Does ``view`` tell ``model`` at ``T_cloud_model`` (4, 4) from the bare table under it? Yes when
    ``need`` of its supported points (``check``) stand clear of the depth tolerance; otherwise, when the
    pose could not show that many and stands at least RESOLVABLE_STEPS disparity steps high, when its
    render explains the measured depth decisively better than the bare table's (the render judge's margin,
    :mod:`psorr.acceptance.render_judge`)."""
    if check.n_support_above_table >= need:
        return True
    plane = view.support_plane
    if plane is None:  # then every supported point counts as clear of the table, and too few are
        return False
    R, t = T_cloud_model[:3, :3], T_cloud_model[:3, 3]
    points, normals = model.points @ R.T + t, model.normals @ R.T
    facing = np.einsum("ij,ij->i", normals, -points) > 0
    if not facing.any():
        return False
    points = points[facing]
    heights = points @ plane[:3] + plane[3]
    could_show = np.mean(heights > depth_tolerance(points[:, 2], params)) * check.n_visible
    step = float(depth_noise().quantisation_step(np.median(points[:, 2])))
    if could_show >= need or np.median(heights) < RESOLVABLE_STEPS * step:
        return False
    centre = R @ model.points.mean(axis=0) + t
    costs, n = table_costs(view, renderer, T_cloud_model, centre, 0.5 * model.diameter)
    return bool(costs[1] - costs[0] > max(RESIDUAL_CAP, DECISIVE_SPREADS * np.sqrt(2.0 * n)))
