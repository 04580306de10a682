"""Shape plus colour: a cloud recognised one segment at a time, each detection carrying its segment's
colour (section 2.3: parts of one shape that differ in colour are told apart before recognition)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from psorr.acceptance.claims import SearchResult
from psorr.segment.pipeline import Segment, Segmentation, SegmentParams, segment
from psorr.types import Detection, DetectionColour, PointCloud

BY_COLOUR_AND_DISTANCE = SegmentParams(crease_noise=None)
"""Segments are not split at creases: the models explain the geometry themselves, and a concave part (a
bracket, a channel) would fall into pieces."""


def search_per_segment(find: Callable[[PointCloud, np.random.Generator], SearchResult], cloud: PointCloud,
                       rng: np.random.Generator) -> SearchResult:
    """Segment ``cloud`` by colour and distance, search each segment alone with ``find`` (a recognizer's
    search of one cloud), and give each detection its segment's colour. The costs add up."""
    detections, results = [], []
    for seg, alone in segment_clouds(cloud, segment(cloud, BY_COLOUR_AND_DISTANCE, rng)):
        results.append(find(alone, rng))
        detections += [coloured(d, seg) for d in results[-1].detections]
    return SearchResult(tuple(detections), *(sum(getattr(r, name) for r in results) for name in
                                             ("hypotheses", "verify_ms", "decomposition_ms", "qpbo_nodes",
                                              "qpbo_unlabelled")))


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
