"""Settings and results of recognition (psorr.recognize)."""

from __future__ import annotations

from dataclasses import dataclass, field

from psorr.acceptance.continuation import ContinuationParams
from psorr.checks import params as check
from psorr.decomposition import DecomposeParams
from psorr.decomposition.support_crop import SupportCropParams
from psorr.hypotheses.single_cylinder import SingleCylinderParams
from psorr.hypotheses.single_plane import SinglePlaneParams
from psorr.types import Detection
from psorr.verification.point_check import CheckParams

METHODS = ("psorr", "orr")


@dataclass(frozen=True)
class RecognizeParams:
    """Settings of recognition; distances in metres."""

    decompose: DecomposeParams = field(default_factory=lambda: DecomposeParams(voxel_size=0.008))
    leftover_voxel: float | None = 0.005  # PSORR: points the decomposition left unlabelled, again at this voxel
    fine_voxel: float | None = 0.005    # PSORR: what stands unexplained after the search, decomposed again
    min_unexplained: int = 100          # PSORR: ... if at least this many points (a detection needs min_support)
    max_hypotheses: int = 100           # PSORR: clustered hypotheses screened by boxes, per round
    cluster_cell: float = 0.02          # PSORR: position grid of the vote clustering
    min_box_score: float = 0.1
    box_thickness: float = 0.04         # boxes are thickened to this: pair poses are off by a centimetre or so
    refine_top: int = 24                # best screened hypotheses that get ICP and the point check
    pair_rounds: int = 2                # PSORR: pairing again among the primitives detections leave unexplained
    orr_hypotheses: int = 1500          # ORR: hypotheses drawn and checked point by point
    icp_distance: float = 0.012
    icp_points: int = 1500              # model points in the fine ICP (3000: a fifth more time, 0.05 mm better ADD)
    check: CheckParams = field(default_factory=CheckParams)
    min_visible_fraction: float = 0.35
    min_unblocked_fraction: float = 0.6  # or, for a part partly hidden by others, of its unhidden points
    max_violation_ratio: float = 0.15
    min_support: int = 60
    # ... of which this many higher above the supporting plane than their depth tolerance: the table explains
    # the rest as well. A circuit board lying flat is supported by the table wherever it is posed on it; ORR
    # placed 7 on the far table of 45 real clouds (README, "Real clouds that hold none of our parts").
    # True detections in heavy clutter kept 63 or more. 0 turns this off, for a part so thin (a bare plate)
    # that nothing of it stands higher than the tolerance.
    min_support_above_table: int = 30
    max_float: float | None = 0.02      # a part's lowest point this far above the supporting plane is no part
    max_shared_pixels: float = 0.3      # a detection sharing more of its pixels with a better one is dropped
    # A pose around whose outline more of the measured surface than this goes on in its faces' planes sits on a
    # larger object (psorr.acceptance.continuation): an L bracket in a box's corner. None turns the check off (it costs
    # about 2 ms a scene); parts flush with larger objects (stacked edge to edge, in a fitting corner) need it
    # off. Measured in the README, "Real clouds that hold none of our parts".
    max_continued: float | None = 0.2
    continuation: ContinuationParams = field(default_factory=ContinuationParams)
    single_plane: SinglePlaneParams = field(default_factory=SinglePlaneParams)  # PSORR: poses from one face
    single_cylinder: SingleCylinderParams = field(default_factory=SingleCylinderParams)  # ... and one cylinder
    support_crop: SupportCropParams = field(default_factory=SupportCropParams)  # PSORR: what is decomposed

    def __post_init__(self):
        check.whole(self, "max_hypotheses", "refine_top", "pair_rounds", "orr_hypotheses", "min_support",
                    "min_unexplained", "icp_points")
        check.whole(self, "min_support_above_table", minimum=0, note=" (0 turns it off)")
        check.positive(self, "leftover_voxel", "fine_voxel", "max_float", unit=" metres", optional=True)
        check.positive(self, "cluster_cell", "box_thickness", "icp_distance", unit=" metres")
        check.within(self, "min_box_score", "min_visible_fraction", "min_unblocked_fraction", "max_violation_ratio",
                     "max_shared_pixels")
        check.within(self, "max_continued", optional=True)
        for name, cls in (("decompose", DecomposeParams), ("check", CheckParams),
                          ("continuation", ContinuationParams), ("single_plane", SinglePlaneParams),
                          ("single_cylinder", SingleCylinderParams),
                          ("support_crop", SupportCropParams)):
            check.instance(self, name, cls)


@dataclass(frozen=True)
class RecognitionStats:
    method: str
    hypotheses: int
    verify_ms_per_hypothesis: float
    decomposition_ms: float
    total_ms: float
    train_ms: float


@dataclass(frozen=True)
class Recognition:
    detections: tuple[Detection, ...]
    stats: RecognitionStats
