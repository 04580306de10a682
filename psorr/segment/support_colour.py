"""The colour of a detection from the points that support it: for a recognizer run on shape alone, whose
detections carry no segment, and for a robot that picks a part by its colour."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from psorr.errors import InvalidInputError
from psorr.segment.colour import colour_name, rgb_to_lab
from psorr.types import Detection, DetectionColour, PointCloud
from psorr.verification.point_check import CheckParams, depth_tolerance

LIT_SHARE = 0.5  # the share of a part's supporting points, brightest first, whose colour it is seen in


def supported_colour(cloud: PointCloud, detection: Detection, model, params: CheckParams | None = None
                     ) -> DetectionColour | None:
    """The colour of the points of ``cloud`` that lie on ``detection``'s model surface at its pose.

    A point lies on the surface when it is within the point check's depth tolerance at its depth (the sensor's
    noise there, ``params``) of the posed model's samples, widened by the samples' own spacing. The colour is
    the per-channel median over the better-lit half of those points (by CIELAB lightness): faces turned from
    the light show the part darker than it is (a brown part reads black), and the median keeps the table's
    rim of points along the part's foot, stray points of a neighbour and specular highlights from tinting it
    (decision 0060).

    Args:
        cloud: the cloud the detection was found in (metres; with ``colors``).
        detection: a detection of ``model`` in ``cloud``.
        model: the detection's :class:`psorr.library.models.Model` (``library.model(detection.model)``).
        params: the point check's tolerances (default: ``CheckParams()``).

    Returns:
        The colour and its palette name, or None when the cloud has no colours or no point lies on the surface.
    """
    if model.name != detection.model:
        raise InvalidInputError(f"the detection is of {detection.model!r}, not of the model {model.name!r} given; "
                                "pass library.model(detection.model)")
    if cloud.colors is None:
        return None
    on = supporting_points(cloud, detection, model, params)
    if len(on) == 0:
        return None
    colours = np.asarray(cloud.colors, dtype=np.float64)[on]
    lightness = rgb_to_lab(colours)[:, 0]
    lit = colours[lightness >= np.quantile(lightness, 1.0 - LIT_SHARE)]
    rgb = np.median(lit, axis=0)
    return DetectionColour(colour_name(rgb), tuple(float(v) for v in rgb))


def supporting_points(cloud: PointCloud, detection: Detection, model, params: CheckParams | None = None
                      ) -> np.ndarray:
    """Indices (K,) into ``cloud.points`` of the points on ``detection``'s model surface at its pose: within
    the point check's depth tolerance at their depth (``params``, default ``CheckParams()``) of the posed
    model's samples, widened by the samples' own spacing."""
    params = CheckParams() if params is None else params
    T = detection.T_cloud_model
    surface = model.points @ T[:3, :3].T + T[:3, 3]
    spacing = _spacing(model.points)
    reach = depth_tolerance(np.array([surface[:, 2].max()]), params)[0] + spacing
    points = cloud.points
    with np.errstate(invalid="ignore"):
        near = np.all((points >= surface.min(axis=0) - reach) & (points <= surface.max(axis=0) + reach), axis=1)
    index = np.flatnonzero(near)
    if len(index) == 0:
        return index
    distance, _ = cKDTree(surface).query(points[index], distance_upper_bound=reach)
    return index[distance <= depth_tolerance(points[index, 2], params) + spacing]


def _spacing(samples: np.ndarray) -> float:
    """The samples' typical spacing (m): the median distance from a sample to its nearest other one, over at
    most 200 samples taken evenly."""
    probe = samples[:: max(1, len(samples) // 200)]
    distance, _ = cKDTree(samples).query(probe, k=2)
    return float(np.median(distance[:, 1]))
