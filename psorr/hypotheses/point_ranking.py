"""Poses from a single primitive, ranked by a coarse point check.

One scene face or one long cylinder covers too little of a model's primitive boxes for box
verification to rank its poses; a coarse point check against the depth buffer can. The best few,
shared out across models, go on to acceptance.
"""

from __future__ import annotations

import time

import numpy as np

from psorr.hypotheses.candidates import CandidateSet
from psorr.hypotheses.pose_clusters import share_out
from psorr.verification.point_check import CheckParams, check_poses


class SinglePrimitiveMatcher:
    """A matcher of single scene primitives to the library's models (``models``): its ``hypotheses(primitives)``
    give poses (K, 4, 4) and model indices (K,); its ``params`` hold ``check``, ``min_score`` and ``top``."""

    models: list
    params: object

    def hypotheses(self, primitives) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def candidates(self, view, primitives) -> CandidateSet:
        """The poses of :meth:`hypotheses`, ranked by the coarse point check in ``view`` (a SceneView)."""
        p = self.params
        poses, owners = self.hypotheses(primitives)
        return ranked_by_point_check(view, self.models, poses, owners, p.check, p.min_score, p.top)


def ranked_by_point_check(view, models, poses: np.ndarray, owners: np.ndarray, check: CheckParams,
                          min_score: float, top: int) -> CandidateSet:
    """The ``top`` of ``poses`` (K, 4, 4) ``T_cloud_model`` of ``models`` (the library's, indexed by ``owners``
    (K,)) scoring at least ``min_score`` by the point check ``check`` in ``view`` (a SceneView), best first and
    shared out across models. The time counted is the check's, as the pairs count their box scores'."""
    if not len(poses):
        return CandidateSet()
    t1 = time.perf_counter()
    checks = check_poses(view, [models[m].points for m in owners], [models[m].normals for m in owners], poses, check)
    scores = np.array([c.score for c in checks])
    order = np.argsort(-scores, kind="stable")
    order = share_out(order[scores[order] >= min_score], owners, top)
    verify_ms = (time.perf_counter() - t1) * 1e3
    return CandidateSet.chosen(owners, poses, order, len(poses), verify_ms, scores)
