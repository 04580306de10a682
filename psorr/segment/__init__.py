"""Segmentation of a table-top cloud into objects by colour and distance (section 2.3 of the paper):
a graph cut over colour models in CIELAB, then conditional Euclidean clustering, then a split where a
segment's surface folds inwards, as objects that touch do (psorr.segment.convexity). A detection found on
shape alone is given the colour of the points that support it by ``supported_colour``."""

from psorr.segment.colour import PALETTE, colour_name, rgb_to_lab
from psorr.segment.pipeline import Segment, Segmentation, SegmentParams, SegmentStats, segment
from psorr.segment.support_colour import supported_colour

__all__ = ["PALETTE", "Segment", "SegmentParams", "SegmentStats", "Segmentation", "colour_name", "rgb_to_lab",
           "segment", "supported_colour"]
