"""The depth-noise model of the recognition in progress: the sensor's, as ``RecognizeParams.sensor`` gives it.

Every threshold that scales with the sensor's noise (the decomposition's inlier distance, the point check's
tolerance, what stands on the table, the thinning of a finer cloud) reads it from :func:`depth_noise`, which
is :data:`~psorr.sensing.kinect_noise.KINECT_V1` unless a recognition set another for its stages. A context
variable carries it, as the observer is carried (:mod:`psorr.viz.observer`), rather than an argument through
every stage: the stages that read it sit several calls deep, under functions that serve other callers too.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from contextvars import ContextVar

from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise

_CURRENT: ContextVar[KinectNoise] = ContextVar("psorr_depth_noise", default=KINECT_V1)


def depth_noise() -> KinectNoise:
    """The depth-noise model of the recognition in progress (the Kinect v1's outside one)."""
    return _CURRENT.get()


@contextlib.contextmanager
def noise_model(model: KinectNoise) -> Iterator[KinectNoise]:
    """Make ``model`` the depth-noise model of the stages run inside the block."""
    token = _CURRENT.set(model)
    try:
        yield model
    finally:
        _CURRENT.reset(token)
