"""ORR hypotheses (Papazov and Burschka 2010): random oriented scene point pairs looked up in the same hash
table, each pose screened point by point (psorr.verification.point_check, many poses at once)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from psorr.checks import params as check
from psorr.hypotheses.candidates import Candidate, CandidateSet
from psorr.library.models import ModelLibrary
from psorr.verification.point_check import CheckParams, check_poses

# Hypotheses checked at once (Table 1's scenes: 32, 64 and 128 cost the same per hypothesis; one at a
# time cost 2.7x as much).
_BATCH = 64


@dataclass(frozen=True)
class OrrParams:
    """Settings of the ORR baseline: ``hypotheses`` poses are drawn and point-checked (``check``); those
    with at least ``min_support`` supported points, the ``refine_top`` best, go on to acceptance."""

    hypotheses: int = 1500
    refine_top: int = 24
    min_support: int = 30  # half of acceptance's: a rough random-pair pose is supported by fewer points
    check: CheckParams = field(default_factory=CheckParams)

    def __post_init__(self):
        check.whole(self, "hypotheses", "refine_top", "min_support")
        check.instance(self, "check", CheckParams)


def orr_hypotheses(library: ModelLibrary, view, params: OrrParams, rng: np.random.Generator) -> CandidateSet:
    """The best point-checked poses of random oriented point pairs of ``view`` (a SceneView) off its supporting
    plane, with the number of hypotheses drawn and the ms their checks took."""
    # Oriented scene points: the view's ICP copy already carries normals facing the sensor.
    # Papazov samples the scene with the supporting plane segmented away.
    pts = view.object_points
    nrm = np.asarray(view.objects.normals)
    if len(nrm) < 2:  # fewer than 3 points off the table get no normals: nothing to pair
        return CandidateSet()
    poses, models = _draw(library, view.object_tree, pts, nrm, params.hypotheses, rng)
    # No draw depends on a check, so the hypotheses are checked in batches, as PSORR's boxes are:
    # one at a time, numpy's per-call overhead cost as much as the check itself.
    scored, elapsed = [], 0.0
    for start in range(0, len(poses), _BATCH):
        batch, owners = np.array(poses[start:start + _BATCH]), models[start:start + _BATCH]
        t0 = time.perf_counter()
        checks = check_poses(view, [library.models[m].points for m in owners],
                             [library.models[m].normals for m in owners], batch, params.check)
        elapsed += (time.perf_counter() - t0) * 1e3
        scored += [(c.score, m, T) for c, m, T in zip(checks, owners, batch) if c.n_support >= params.min_support]
    scored.sort(key=lambda s: -s[0])
    return CandidateSet(tuple(Candidate(m, T) for _, m, T in scored[: params.refine_top]), len(poses), elapsed)


def _draw(library: ModelLibrary, tree, pts: np.ndarray, nrm: np.ndarray, wanted: int,
          rng: np.random.Generator) -> tuple[list[np.ndarray], list[int]]:
    """About ``wanted`` poses (4, 4) and their model indices from random pairs of the oriented points ``pts``,
    ``nrm`` (N, 3) (``tree``: their k-d tree), looked up in the library's pair table; at most 20 draws a pose."""
    diameters = np.array([m.diameter for m in library.models])
    drawn_poses, drawn_models = [], []
    attempts = 0
    while len(drawn_poses) < wanted and attempts < 20 * wanted:
        attempts += 1
        a = int(rng.integers(len(pts)))
        # Papazov draws the second point at a fixed distance from the first: a
        # share of the model size, so both points often lie on one object.
        radius = float(rng.uniform(0.3, 0.8) * np.median(diameters))
        _, idx, _ = tree.search_radius_vector_3d(pts[a], radius)
        idx = np.asarray(idx)
        if len(idx) < 2:
            continue
        far = idx[np.linalg.norm(pts[idx] - pts[a], axis=1) > 0.6 * radius]
        if len(far) == 0:
            continue
        b = int(rng.choice(far))
        # Papazov looks a pair up in its own cell only. Raw points are as dense as the model's
        # samples, so the cell holds the match; the neighbouring cells' extra matches would only
        # dilute the few poses drawn from them.
        s, rows = library.table.lookup(pts[[a]], nrm[[a]], pts[[b]], nrm[[b]], neighbours=False)
        if len(rows) == 0:
            continue
        pick = rng.choice(len(rows), size=min(len(rows), 4), replace=False)
        poses, models = library.table.poses(s[pick], rows[pick], pts[[a]], nrm[[a]], pts[[b]])
        drawn_poses.extend(poses)
        drawn_models.extend(int(m) for m in models)
    return drawn_poses, drawn_models
