"""The sensor's lateral jitter in render and compare: a pixel may measure its neighbour's depth.

A structured-light sensor's depth at a pixel is matched from a patch of the projected pattern, and where
the patch straddles an edge it is read a pixel or so aside: the Kinect model of
:class:`~psorr.sensing.kinect_noise.KinectNoise` jitters where each pixel samples by a normal of
``lateral_sigma_px`` sensor pixels, rounded to a pixel (about half the pixels of a Kinect v1 read a
neighbour's depth). Away from edges that changes nothing; at an edge a pixel measures either side. A 4 mm
hole through a plate, three pixels wide at 0.7 m, measures the plate's top in half its pixels.

Scored as if each pixel measured its own ray, a pose that renders the hole where it is pays for every
pixel that read the plate, up to a 3-sigma miss each, and a pose that renders no hole pays only where
the hole showed: the wrong pose can cost less. The likelihood of a measurement is instead the mixture over
the pixels it may have come from, each weighted by how likely the jitter takes it there, and its cost
-2 log of that: where every neighbour renders alike, the squared residual as before.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

from psorr.sensing.kinect_noise import KinectNoise

SMALLEST_WEIGHT = 1e-3  # offsets the jitter takes a pixel to less often than this are left out of the mixture


def own_pixel() -> tuple[np.ndarray, np.ndarray]:
    """The mixture of a pixel read along its own ray alone: the offset (0, 0) (1, 2) of weight 1 (1,)."""
    return np.zeros((1, 2), dtype=np.int64), np.ones(1)


def jitter_offsets(noise: KinectNoise) -> tuple[np.ndarray, np.ndarray]:
    """The pixel offsets (J, 2) (du, dv), (0, 0) first, that the sensor's lateral jitter takes a pixel's
    sample to, and how likely each is (J,), summing to 1: a normal of ``lateral_sigma_px`` pixels on each
    axis, rounded to a pixel. A depth buffer's pixel is the sensor's (:class:`SceneView` takes an organised
    cloud's own focal length, and a scattered cloud's from its spacing). Only (0, 0) for a sensor without
    lateral jitter."""
    if not noise.lateral:
        return own_pixel()
    sigma = noise.lateral_sigma_px
    reach = int(np.ceil(6 * sigma)) + 1
    steps = np.arange(-reach, reach + 1)
    per_axis = ndtr((steps + 0.5) / sigma) - ndtr((steps - 0.5) / sigma)  # round(N(0, sigma)) = step
    du, dv = np.meshgrid(steps, steps)
    weights = np.outer(per_axis, per_axis).ravel()
    offsets = np.column_stack([du.ravel(), dv.ravel()])
    keep = weights >= SMALLEST_WEIGHT
    order = np.argsort(-weights[keep], kind="stable")  # the pixel itself, the likeliest, first
    offsets, weights = offsets[keep][order], weights[keep][order]
    return offsets.astype(np.int64), weights / weights.sum()


def mixture_costs(rendered: np.ndarray, observed: np.ndarray, sigma: np.ndarray, weights: np.ndarray,
                  cap: float) -> np.ndarray:
    """(K, P) the cost, -2 log of the mixture likelihood in squared sigmas and at most ``cap``, of each
    measured depth ``observed`` (P,) under each of K renders ``rendered`` (K, P, J) at the pixels the jitter
    may have sampled it from, of ``weights`` (J,): where all J render alike, the squared residual over
    ``sigma`` (P,). A render that misses where the sensor measured costs the cap there."""
    with np.errstate(invalid="ignore"):
        residual = (rendered - observed[None, :, None]) / sigma[None, :, None]
    squared = np.minimum(np.where(np.isfinite(residual), residual**2, cap), cap)
    likelihood = np.exp(-0.5 * squared) @ weights
    return np.minimum(-2.0 * np.log(likelihood), cap)
