"""Settings of acceptance: the ICP that fits a candidate, and the bars its point check must clear."""

from __future__ import annotations

from dataclasses import dataclass, field

from psorr.acceptance.continuation import ContinuationParams
from psorr.checks import params as check
from psorr.verification.point_check import CheckParams


@dataclass(frozen=True)
class AcceptParams:
    """Settings of acceptance; distances in metres, shares in [0, 1].

    A candidate is fitted by point-to-plane ICP pairing points within ``icp_distance``, then its rendered
    surface is fitted to the measured depth over the pixels within a third of that distance of the model
    (:func:`psorr.acceptance.projective.refine_projective`), then point-checked (``check``). It is accepted
    when at least ``min_visible_fraction`` of its surface is measured, or, for a part partly hidden by
    others, ``min_unblocked_fraction`` of its unhidden points; when at least ``min_support`` points are
    supported, ``min_support_above_table`` of them higher above the supporting plane than their depth
    tolerance (a part too thin at its depth to show that many is judged against the bare table instead:
    :mod:`psorr.acceptance.thin_parts`); when at most ``max_violation_ratio`` of the measured points are
    seen through; when its lowest point is no more than ``max_float`` above the supporting plane, and none
    lies inside the table deeper than its depth tolerance (:func:`psorr.acceptance.accept.sinks_into_table`); and when
    the measured surface goes on past its outline on no more than ``max_continued`` of a ring around it
    (``continuation``). A detection sharing more than ``max_shared_pixels`` of its pixels with a better one
    is dropped.
    """

    icp_distance: float = 0.012
    check: CheckParams = field(default_factory=CheckParams)
    min_visible_fraction: float = 0.35
    min_unblocked_fraction: float = 0.6
    max_violation_ratio: float = 0.05
    min_support: int = 60
    # The table explains the rest as well: a circuit board lying flat is supported by the table wherever
    # it is posed on it. 0 turns this off. Measured: docs/decisions/0024-support-above-table.md.
    min_support_above_table: int = 30
    max_float: float | None = 0.02  # None: parts piled on one another
    max_shared_pixels: float = 0.3
    # None turns the check off (it costs about 2 ms a scene): parts flush with larger objects (stacked edge
    # to edge, in a fitting corner) need it off. Measured: docs/decisions/0026-continuation-check.md.
    max_continued: float | None = 0.1
    continuation: ContinuationParams = field(default_factory=ContinuationParams)

    def __post_init__(self):
        check.whole(self, "min_support")
        check.whole(self, "min_support_above_table", minimum=0, note=" (0 turns it off)")
        check.positive(self, "max_float", unit=" metres", optional=True)
        check.positive(self, "icp_distance", unit=" metres")
        check.within(self, "min_visible_fraction", "min_unblocked_fraction", "max_violation_ratio",
                     "max_shared_pixels")
        check.within(self, "max_continued", optional=True)
        check.instance(self, "check", CheckParams)
        check.instance(self, "continuation", ContinuationParams)
