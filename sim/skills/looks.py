"""What a look returns: the estimates of one look at the cell, and a look at a part held in the hand."""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from psorr.types import Detection, PointCloud
from sim.devices.sensor import SensorFrame


class Estimate(NamedTuple):
    """One detection of a part, in the world frame.

    Attributes:
        T_world_part: (4, 4) the part's pose.
        score: the detection's score, in [0, 1].
        alternatives: its near-symmetric twins (4, 4, world) that the look could not rule out
            (:attr:`psorr.types.Detection.alternatives`).
        colour: the palette name of the colour the look saw it in (``psorr.segment.supported_colour``), or None
            when the look did not name colours.
    """

    T_world_part: np.ndarray
    score: float
    alternatives: tuple = ()
    colour: str | None = None


@dataclass(frozen=True, eq=False)
class Look:
    """One look at the cell before a pick.

    Attributes:
        frame: the Kinect frame (None when the look was an oracle's occupancy check only).
        detections: PSORR's detections in the camera frame (empty for the oracle).
        estimates: per part, its detections as :class:`Estimate` s, best score first.
        intruding: how many points are above the workspace that neither a part nor the robot explains.
        occupied: ``intruding`` reaches the threshold: someone is reaching in.
    """

    frame: SensorFrame | None
    detections: tuple[Detection, ...]
    estimates: MappingProxyType
    intruding: int
    occupied: bool


@dataclass(frozen=True, eq=False)
class HeldLook:
    """A look at a part held up in the hand: PSORR's ``detection`` of it (camera frame), ``T_world_camera``
    (4, 4), and the look's cloud ``with_arm``, the arm's points kept, which shows what the fingers hide."""

    detection: Detection
    T_world_camera: np.ndarray
    with_arm: PointCloud
