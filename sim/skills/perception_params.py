"""How the robot looks: which recognizer it runs and how noisy its Kinect is (swept by ``psorr-sim sweep``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from psorr.recognize import Method
from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise
from sim.errors import SimInputError


@dataclass(frozen=True)
class PerceptionParams:
    """The look's recognizer and sensor noise.

    Attributes:
        method: the recognizer, a :class:`psorr.types.Method` value (``"psorr"``, ``"psg"``, ``"auto"``, ``"orr"``).
        noise_scale: the Kinect v1's axial depth noise (:data:`psorr.sensing.kinect_noise.KINECT_V1`, a standard
            deviation growing with the square of the depth) times this; 1 is the real sensor, 0 exact depth
            along the ray. The lateral jitter, disparity steps and dropouts stay the Kinect's.
    """

    method: str = Method.PSORR.value
    noise_scale: float = 1.0

    def __post_init__(self):
        methods = [m.value for m in Method]
        if self.method not in methods:
            raise SimInputError(f"unknown recognizer method {self.method!r}; choose one of {methods}")
        if isinstance(self.noise_scale, bool) or not isinstance(self.noise_scale, (int, float)) \
                or not 0 <= self.noise_scale <= 10:
            raise SimInputError(f"noise_scale must be a number in [0, 10] (1 is the Kinect v1), "
                                f"got {self.noise_scale!r}")

    @property
    def noise(self) -> KinectNoise:
        """The sensor's noise model."""
        if self.noise_scale == 1:
            return KINECT_V1
        return dataclasses.replace(KINECT_V1, sigma_base=KINECT_V1.sigma_base * self.noise_scale,
                                   sigma_quad=KINECT_V1.sigma_quad * self.noise_scale)
