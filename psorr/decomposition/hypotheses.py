"""RANSAC shape hypotheses from oriented points.

A plane comes from one point and its normal. A cylinder comes from two
nearby points and their normals: its axis is the shortest line between the
two normal lines. Candidates are scored on a random subset of the points not
yet explained (Schnabel et al. 2007), the winners refitted on all of them,
and the rounds repeat until several in a row find nothing new.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.decomposition.preprocess import Voxelized
from psorr.geometry import shapes
from psorr.types import PrimitiveKind


@dataclass(frozen=True)
class ShapeHypothesis:
    kind: PrimitiveKind
    params: tuple[float, ...]


def support_mask(kind, params, points, normals, threshold, cos_max_angle):
    """(N,) bool: points within `threshold` (scalar or (N,)) of the shape whose
    normals agree with it to within the angle."""
    close = shapes.distances(kind, params, points) < threshold
    agree = shapes.normal_agreement(kind, params, points, normals) > cos_max_angle
    return close & agree


def _plane_candidates(points, normals, seeds) -> np.ndarray:
    n = normals[seeds]
    return np.column_stack([n, -np.einsum("ij,ij->i", n, points[seeds])])


def _cylinder_candidates(vox: Voxelized, seeds, rng, radius_range) -> np.ndarray:
    # A partner from the far half of the neighbourhood: normals further apart
    # pin the axis down better.
    k = vox.neighbours.shape[1]
    partner = vox.neighbours[seeds, rng.integers(k // 2, k, len(seeds))]
    params, _ = shapes.cylinders_from_point_pairs(
        vox.points[seeds], vox.normals[seeds], vox.points[partner], vox.normals[partner]
    )
    ok = (params[:, 6] >= radius_range[0]) & (params[:, 6] <= radius_range[1])
    return params[ok]


def generate_hypotheses(vox: Voxelized, threshold, params, rng) -> tuple[list[ShapeHypothesis], np.ndarray]:
    """Shape hypotheses for the voxelised cloud.

    Args:
        threshold: (M,) inlier distance per voxel, metres.
        params: a DecomposeParams.
    Returns (hypotheses, claimed (M,) index of the hypothesis that claimed each
    voxel, or -1): the claims seed the graph cut.
    """
    cos_max = np.cos(np.radians(params.max_normal_angle_deg))
    m = len(vox)
    claimed = np.full(m, -1, dtype=np.int64)
    hypotheses: list[ShapeHypothesis] = []
    misses = 0
    while misses < params.ransac_patience and len(hypotheses) < params.max_primitives:
        free = np.flatnonzero(claimed < 0)
        if len(free) < params.min_points:
            break
        seeds = rng.choice(free, size=min(params.ransac_candidates, len(free)), replace=False)
        sample = free if len(free) <= params.ransac_sample else rng.choice(free, params.ransac_sample, replace=False)
        pts, nrm, thr = vox.points[sample], vox.normals[sample], threshold[sample]
        planes = _plane_candidates(vox.points, vox.normals, seeds)
        candidates = [(PrimitiveKind.PLANE, tuple(p)) for p in planes]
        scores = [shapes.support_counts(PrimitiveKind.PLANE, planes, pts, nrm, thr, cos_max)]
        if params.cylinders:
            cylinders = _cylinder_candidates(vox, seeds, rng, params.cylinder_radius_range)
            candidates += [(PrimitiveKind.CYLINDER, tuple(p)) for p in cylinders]
            scores.append(shapes.support_counts(PrimitiveKind.CYLINDER, cylinders, pts, nrm, thr, cos_max))
        scores = np.concatenate(scores)
        scale = len(free) / len(sample)
        accepted_round = 0
        taken = np.zeros(len(sample), dtype=bool)
        for c in np.argsort(-scores, kind="stable"):
            if scores[c] * scale < params.min_points or accepted_round >= params.ransac_accept_per_round:
                break
            kind, p = candidates[c]
            sample_support = support_mask(kind, p, pts, nrm, thr, cos_max)
            # Skip a candidate that mostly re-explains a winner of this round.
            if (sample_support & taken).sum() > 0.3 * sample_support.sum():
                continue
            fitted = _refit_on_free(kind, p, vox, free, threshold, cos_max, params.cylinder_radius_range[1])
            if fitted is None or len(fitted[1]) < params.min_points:
                continue
            p, support = fitted
            taken |= support_mask(kind, p, pts, nrm, thr, cos_max)
            claimed[support] = len(hypotheses)
            hypotheses.append(ShapeHypothesis(kind, p))
            accepted_round += 1
            free = np.flatnonzero(claimed < 0)
        misses = 0 if accepted_round else misses + 1
    return hypotheses, claimed


def _refit_on_free(kind, p, vox, free, threshold, cos_max, max_radius, iterations: int = 2):
    pts, nrm, thr = vox.points[free], vox.normals[free], threshold[free]
    support = support_mask(kind, p, pts, nrm, thr, cos_max)
    for _ in range(iterations):
        if support.sum() < 6:
            return None
        refit = shapes.fit(kind, pts[support], nrm[support], max_radius=max_radius)
        if refit is None:
            return None
        new_support = support_mask(kind, refit, pts, nrm, thr, cos_max)
        if new_support.sum() < support.sum():
            break
        p, support = refit, new_support
    return tuple(float(v) for v in p), free[support]
