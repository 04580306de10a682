"""ORR hypotheses (Papazov and Burschka, ACCV 2010): random oriented scene point pairs at the pair width d,
looked up in ORR's own table of dense model pairs (psorr.library.orr_table), each pose screened point by
point against the depth buffer (psorr.verification.point_check, many poses at once).

The number of pairs drawn is Papazov's bound. A pair is drawn by taking a first point uniformly among the
scene's K leaves off the supporting plane, then a second among the leaves d apart from it. It lies on a
model instance covering K_M of the leaves with probability P_M = (K_M / K) x p, p being the chance that the
second point lies on the instance when the first does. N pairs find that instance at least once with
probability 1 - (1 - P_M)^N, which reaches P_S for N = ln(1 - P_S) / ln(1 - P_M).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from psorr.checks import params as check
from psorr.errors import InvalidInputError
from psorr.hypotheses.candidates import Candidate, CandidateSet
from psorr.hypotheses.pose_clusters import same_pose
from psorr.library.models import ModelLibrary
from psorr.library.orr_table import OrrTable, OrrTableParams, coplanar
from psorr.library.ppf import pair_features
from psorr.verification.point_check import CheckParams, check_poses

# Hypotheses checked at once (Table 1's scenes: 32, 64 and 128 cost the same per hypothesis; one at a
# time cost 2.7x as much).
_BATCH = 64


@dataclass(frozen=True)
class OrrParams:
    """Settings of the ORR baseline (docs/decisions/0020-orr-baseline.md, 0048-orr-budget.md).

    Budget: pairs are drawn until an instance showing ``min_visible`` of the smallest model's front half
    (half its surface, in the table's leaves: K_M) is found with probability ``success_probability``
    (P_S), each pair landing on it with probability (K_M / K) x ``partner_probability`` over the scene's
    K leaves; so the number of pairs scales with the scene's size in voxels over the smallest model's.
    At most K pairs are drawn (no first point twice) and at most ``max_hypotheses`` poses checked.
    Every stored model pair in a drawn pair's cell gives a pose; each is point-checked (``check``), and
    those with at least ``min_support`` supported points, the ``refine_top`` best of distinct poses, go on
    to acceptance. ``table``: how ORR's model table is sampled.
    """

    success_probability: float = 0.99
    min_visible: float = 0.3
    partner_probability: float = 0.25
    max_hypotheses: int = 20000
    refine_top: int = 24
    min_support: int = 30  # half of acceptance's: a rough random-pair pose is supported by fewer points
    check: CheckParams = field(default_factory=CheckParams)
    table: OrrTableParams = field(default_factory=OrrTableParams)

    def __post_init__(self):
        check.within(self, "success_probability", "min_visible", "partner_probability", closed=False)
        check.whole(self, "max_hypotheses", "refine_top", "min_support")
        check.instance(self, "check", CheckParams)
        check.instance(self, "table", OrrTableParams)


def papazov_iterations(success_probability: float, pair_probability: float) -> int:
    """Papazov's N: the fewest draws that find, with probability ``success_probability`` (P_S), something
    each draw finds with probability ``pair_probability`` (P_M): ceil(ln(1 - P_S) / ln(1 - P_M))."""
    if not (0 < success_probability < 1 and 0 < pair_probability <= 1):
        raise InvalidInputError(f"papazov_iterations() takes probabilities P_S in (0, 1) and P_M in (0, 1], got "
                                f"{success_probability!r} and {pair_probability!r}")
    if pair_probability == 1:
        return 1
    return math.ceil(math.log1p(-success_probability) / math.log1p(-pair_probability))


def pairs_to_draw(table: OrrTable, scene_leaves: int, params: OrrParams) -> int:
    """Papazov's N for a scene of ``scene_leaves`` leaves off its supporting plane, at most that many."""
    instance = params.min_visible * table.leaves.min() / 2
    share = min(1.0, instance / max(scene_leaves, 1))
    return min(scene_leaves, papazov_iterations(params.success_probability, share * params.partner_probability))


def orr_hypotheses(library: ModelLibrary, table: OrrTable, view, params: OrrParams,
                   rng: np.random.Generator) -> CandidateSet:
    """The best point-checked poses of random oriented point pairs of ``view`` (a SceneView) off its supporting
    plane, looked up in ``table`` (built for ``library``), with the number of hypotheses checked and the ms
    their checks took."""
    # Oriented scene leaves: the view's ICP copy, voxelised as the table's leaves are, with normals facing
    # the sensor. Papazov samples the scene with the supporting plane segmented away.
    pts = view.object_points
    nrm = np.asarray(view.objects.normals)
    if len(nrm) < 2:  # fewer than 3 points off the table get no normals: nothing to pair
        return CandidateSet()
    first, second = _draw(table, pts, nrm, pairs_to_draw(table, len(pts), params), rng)
    poses, models = table.poses(pts[first], nrm[first], pts[second], nrm[second])
    if len(poses) > params.max_hypotheses:  # the cap: an even share of every drawn pair's matches
        keep = np.sort(rng.choice(len(poses), size=params.max_hypotheses, replace=False))
        poses, models = poses[keep], models[keep]
    # No draw depends on a check, so the hypotheses are checked in batches, as PSORR's boxes are:
    # one at a time, numpy's per-call overhead cost as much as the check itself.
    scores, elapsed = np.zeros(len(poses)), 0.0
    for start in range(0, len(poses), _BATCH):
        batch, owners = poses[start:start + _BATCH], models[start:start + _BATCH]
        t0 = time.perf_counter()
        checks = check_poses(view, [library.models[m].points for m in owners],
                             [library.models[m].normals for m in owners], batch, params.check)
        elapsed += (time.perf_counter() - t0) * 1e3
        scores[start:start + len(checks)] = [c.score if c.n_support >= params.min_support else -1.0 for c in checks]
    chosen = _distinct_best(library, poses, models, scores, params.refine_top)
    return CandidateSet(tuple(Candidate(int(models[k]), poses[k]) for k in chosen), len(poses), elapsed)


def _draw(table: OrrTable, pts: np.ndarray, nrm: np.ndarray, wanted: int,
          rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Indices (first, second) into the oriented leaves ``pts``, ``nrm`` (K, 3) of up to ``wanted`` pairs:
    distinct first points, each with a second drawn among the leaves d +- delta from it. A first point
    with no such leaf, or whose pair lies in one plane (the table stores none), gives no pair."""
    width, band = table.width, table.params.band
    firsts = rng.choice(len(pts), size=wanted, replace=False)
    near = cKDTree(pts).query_ball_point(pts[firsts], width + band)
    pairs = []
    for a, candidates in zip(firsts, near):
        candidates = np.asarray(candidates, dtype=np.int64)
        ring = candidates[np.linalg.norm(pts[candidates] - pts[a], axis=1) >= width - band]
        if len(ring):
            pairs.append((a, int(rng.choice(ring))))
    first, second = np.array(pairs, dtype=np.int64).reshape(-1, 2).T
    angles, _ = pair_features(pts[first], nrm[first], pts[second], nrm[second])
    flat = coplanar(angles, np.radians(table.params.angle_cell_deg))
    return first[~flat], second[~flat]


def _distinct_best(library: ModelLibrary, poses: np.ndarray, models: np.ndarray, scores: np.ndarray,
                   wanted: int) -> list[int]:
    """Indices of up to ``wanted`` poses with a score (>= 0), best first, none the same pose of the same model
    as a better one (within a tenth of its diameter: Papazov keeps the best of conflicting hypotheses)."""
    chosen: list[int] = []
    for k in np.argsort(-scores, kind="stable"):
        if scores[k] < 0 or len(chosen) == wanted:
            break
        model = library.models[models[k]]
        if not any(models[j] == models[k] and same_pose(model.points[::50], poses[j], poses[k], 0.1 * model.diameter)
                   for j in chosen):
            chosen.append(int(k))
    return chosen
