"""PSORR's pair stage: pose hypotheses from pairs of scene primitives, screened by their boxes.

The oriented points of two scene primitives (plane centroids and normals, cylinder axes) are looked
up in the model library's hash table; each match gives a pose T = F_model F_scene^-1 (section 2.1.3).
Matches whose primitives could not be parts of their model primitives (kind, size) are dropped, the
poses are clustered by vote, and the best of them by box score (section 2.1.4) go on to ICP and
acceptance.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from psorr.checks import params as check
from psorr.hypotheses.candidates import CandidateSet
from psorr.hypotheses.pose_clusters import densest_poses, share_out
from psorr.hypotheses.primitive_match import PrimitiveSizes
from psorr.library.models import ModelLibrary
from psorr.verification.box_score import PrimitiveArrays, box_scores


@dataclass(frozen=True)
class PairParams:
    """Settings of the pair stage; distances in metres.

    Each round clusters the pair poses by vote (on a ``cluster_cell`` position grid) and keeps the
    ``max_hypotheses`` best-supported, an equal share per model of the library and never fewer than
    ``least_per_model`` a model (the share 100 gives the 10 models it was set on); those are screened
    by box score, with the boxes thickened to ``box_thickness`` (pair poses are off by a centimetre or
    so), and the ``refine_top`` best scoring at least ``min_box_score`` (shared out across models) go on
    to acceptance. After a round's detections, the pairs are made again among the primitives they leave
    unexplained, for up to ``pair_rounds`` rounds.
    """

    max_hypotheses: int = 100
    least_per_model: int = 10
    cluster_cell: float = 0.02
    min_box_score: float = 0.1
    box_thickness: float = 0.04
    refine_top: int = 24
    pair_rounds: int = 2

    def __post_init__(self):
        check.whole(self, "max_hypotheses", "least_per_model", "refine_top", "pair_rounds")
        check.positive(self, "cluster_cell", "box_thickness", unit=" metres")
        check.within(self, "min_box_score")


class PairCandidates:
    """The library's models, prepared for pairing: primitive sizes, boxes and centres."""

    def __init__(self, library: ModelLibrary, params: PairParams | None = None):
        self.library, self.params = library, params or PairParams()
        self.max_diameter = max(m.diameter for m in library.models)
        self._sizes = PrimitiveSizes(library.models)
        self._model_centres = np.array([m.points.mean(axis=0) for m in library.models])  # (M, 3), model frames
        self.model_primitives = [PrimitiveArrays.of(m.graph.primitives) for m in library.models]

    def __call__(self, pts: np.ndarray, nrm: np.ndarray, scene_prims) -> CandidateSet:
        """Pose hypotheses from pairs of the scene's oriented points (K, 3) and their primitives: matched
        in the hash table, clustered by vote, and the best by box score, with the number of clustered
        hypotheses and the ms spent verifying them."""
        p = self.params
        poses, models = np.empty((0, 4, 4)), np.empty(0, dtype=np.int64)
        if len(pts) >= 2:  # pairs need two oriented points
            i, j = np.nonzero(np.linalg.norm(pts[:, None] - pts[None], axis=2) <= self.max_diameter)
            keep = i != j
            i, j = i[keep], j[keep]
            scene_index, rows = self.library.table.lookup(pts[i], nrm[i], pts[j], nrm[j])
            scene_index, rows = self._plausible(scene_prims, i, j, scene_index, rows)
            if len(rows):
                poses, models = self.library.table.poses(scene_index, rows, pts[i], nrm[i], pts[j])
                poses, models = densest_poses(poses, models, scene_index, self._model_centres, p.cluster_cell,
                                              p.max_hypotheses, p.least_per_model)
        t1 = time.perf_counter()
        scores = box_scores(self.model_primitives, poses, PrimitiveArrays.of(scene_prims), p.box_thickness, models)
        order = np.argsort(-scores, kind="stable")
        order = share_out(order[scores[order] >= p.min_box_score], models, p.refine_top)
        verify_ms = (time.perf_counter() - t1) * 1e3
        return CandidateSet.chosen(models, poses, order, len(poses), verify_ms, scores)

    def _plausible(self, scene_prims, i, j, scene_index, rows):
        """The lookup matches whose scene primitives could be parts of their model primitives (kind, size)."""
        table, sizes = self.library.table, self._sizes
        fits = sizes.compatible(scene_prims)
        a, b = table.first[rows], table.second[rows]
        owner = sizes.offsets[table.model[a]]
        keep = fits[i[scene_index], owner + table.primitive[a]] & fits[j[scene_index], owner + table.primitive[b]]
        return scene_index[keep], rows[keep]
