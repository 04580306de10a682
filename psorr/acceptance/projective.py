"""Projective refinement: the model's rendered surface fitted to the measured depth, pixel by pixel.

Point-to-plane ICP pairs each model point with the nearest measured point and pulls it onto that
point's tangent plane, estimated from its noisy neighbours. On a part a few centimetres across, a
Kinect's noise (2-3 mm at a metre) turns those normals askew, and the table's and edges' points pair
with the wrong faces: ICP started *at the truth* took a 40 mm idler 13 mm and 14 degrees away from it,
and a 28 mm hinge 5 mm and 18 degrees (without the noise, within 1 mm and 4 degrees).

Here the pairs are along the sensor's rays instead, as the sensor measures. Each pixel around the
part pairs the point where its ray meets the model's mesh with the point it measured, and the residual
is their distance along the mesh's own normal, which is exact. A pixel whose measurement is further
from the model than GATE_SIGMAS sensor sigmas (the table beside a part a little off, an occluder in
front, a hole seen through) is no pair this iteration. From the same coarse fits, the idler came to
within 2.8 mm and 6.4 degrees, the hinge within 0.8 mm and 4.6 (docs/decisions/0062-projective-refinement.md).
"""

from __future__ import annotations

import numpy as np

from psorr.acceptance.icp import STOP_STEP, damped_step
from psorr.geometry.rotations import from_rotation_vector
from psorr.sensing.noise_context import depth_noise
from psorr.verification.depth_compare import DepthRenderer, pixel_window
from psorr.verification.scene_view import SceneView

# Sensor sigmas within which a pixel's measurement pairs with the model's surface on its ray: 3 keeps
# 99.7% of the pixels a correct pose explains. Measured on the dev singles: 2 sigmas found 35 of 40, 3
# found 34, 4 found 31 (the ICP it replaced: 31).
GATE_SIGMAS = 3.0
ITERATIONS = 10  # most fits stop moving (STOP_STEP) in 6-10; 20 found no more parts
MIN_PAIRS = 12  # pixels: six unknowns need twice as many pairs to be more than fitted noise


def refine_projective(view: SceneView, renderer: DepthRenderer, T_cloud_model: np.ndarray, centre: np.ndarray,
                      radius: float, iterations: int = ITERATIONS) -> np.ndarray:
    """The pose (4, 4) near ``T_cloud_model`` whose rendered surface best fits the measured depth of ``view``
    over the pixels around the sphere (``centre`` (3,), cloud frame; ``radius`` m) that should hold the
    part; ``renderer`` renders the model. Returns ``T_cloud_model`` when fewer than MIN_PAIRS pixels pair."""
    pixels, rays = pixel_window(view, centre, radius)
    measured = view.depth[pixels]
    sigma = depth_noise().depth_sigma(measured)
    measured_points = rays * measured[:, None]
    T = T_cloud_model
    for _ in range(iterations):
        depth, normals = renderer.surface(T, rays)
        with np.errstate(invalid="ignore"):
            paired = np.abs(depth - measured) < GATE_SIGMAS * sigma
        if paired.sum() < MIN_PAIRS:
            break
        p = rays[paired] * depth[paired, None]
        middle = p.mean(axis=0)
        scale = max(float(np.sqrt(((p - middle) ** 2).sum(axis=1).mean())), 1e-6)
        turn, slide = damped_step(p - middle, measured_points[paired] - middle, normals[paired], scale,
                                  weights=sigma[paired] ** -2)
        dR = from_rotation_vector(turn)
        step = np.eye(4)
        step[:3, :3], step[:3, 3] = dR, middle - dR @ middle + slide  # turned about the pairs' middle
        T = step @ T
        if np.linalg.norm(slide) < STOP_STEP and np.linalg.norm(turn) * scale < STOP_STEP:
            break
    return T
