"""Shape plus colour: a cloud recognised one segment at a time, each detection carrying its segment's
colour (section 2.3: parts of one shape that differ in colour are told apart before recognition)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from psorr.segment.pipeline import Segment, Segmentation
from psorr.types import Detection, DetectionColour, PointCloud


def segment_clouds(cloud: PointCloud, segmentation: Segmentation) -> list[tuple[Segment, PointCloud]]:
    """For each segment, ``cloud`` with every other segment's points made NaN: the table and what lies
    off it stay, so recognition still finds the supporting plane. Point order stays."""
    out = []
    for seg in segmentation.segments:
        others = (segmentation.labels >= 0) & (segmentation.labels != seg.id)
        points = cloud.points.copy()
        points[others] = np.nan
        out.append((seg, replace(cloud, points=points)))
    return out


def coloured(detection: Detection, segment: Segment) -> Detection:
    """``detection`` carrying ``segment``'s colour (unchanged when the cloud had none)."""
    if segment.mean_rgb is None:
        return detection
    rgb = tuple(float(v) for v in segment.mean_rgb)
    return replace(detection, colour=DetectionColour(segment.colour, rgb))
