"""Greedy merging of adjacent primitives under the MDL fitness of equation 1.

fitness = (points explained / points) - K * (total descriptor length)

A merge drops one primitive's parameters but may leave some points of the
union unexplained by the refitted shape; it is taken when it raises the
fitness, best first, until none does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.decomposition.hypotheses import support_mask
from psorr.geometry import shapes
from psorr.types import PrimitiveKind


@dataclass
class Piece:
    """A primitive under construction: voxel indices instead of final inliers."""

    kind: PrimitiveKind
    params: tuple[float, ...]
    members: np.ndarray


def mdl_fitness(pieces, n_points: int, k: float) -> float:
    explained = sum(len(p.members) for p in pieces)
    return explained / n_points - k * sum(p.kind.n_params for p in pieces)


def adjacent_pairs(labels, edge_i, edge_j, edge_len, max_gap) -> set[tuple[int, int]]:
    a, b = labels[edge_i], labels[edge_j]
    sel = (a >= 0) & (b >= 0) & (a != b) & (edge_len < max_gap)
    lo, hi = np.minimum(a[sel], b[sel]), np.maximum(a[sel], b[sel])
    return set(zip(lo.tolist(), hi.tolist()))


_SCREEN_POINTS = 300


def _best_merge(pa: Piece, pb: Piece, vox, threshold, cos_max, n_points, k, max_radius):
    union = np.concatenate([pa.members, pb.members])
    pts, nrm, thr = vox.points[union], vox.normals[union], threshold[union]
    # An evenly strided subset screens out hopeless unions (a table and a box
    # side) before any fit on every point.
    screen = slice(None, None, max(1, len(union) // _SCREEN_POINTS))
    best = None
    # Both kinds, always: two planes that tile a small boss are one cylinder.
    for kind in PrimitiveKind:
        rough = shapes.fit(kind, pts[screen], nrm[screen], max_radius=max_radius)
        if rough is None or support_mask(kind, rough, pts[screen], nrm[screen], thr[screen], cos_max).mean() < 0.7:
            continue
        params = shapes.fit(kind, pts, nrm, max_radius=max_radius)
        if params is None or (kind is PrimitiveKind.CYLINDER and _wall_meets_bore(params, pa, pb, vox)):
            continue
        support = support_mask(kind, params, pts, nrm, thr, cos_max)
        # The geometric refinement only polishes a union that nearly fits;
        # running it on hopeless unions (a table and a box side) wastes time.
        if kind is PrimitiveKind.CYLINDER and support.mean() > 0.8:
            refined = shapes.fit(kind, pts, nrm, refine=True, max_radius=max_radius)
            if refined is not None:
                refined_support = support_mask(kind, refined, pts, nrm, thr, cos_max)
                if refined_support.sum() >= support.sum():
                    params, support = refined, refined_support
        gain = (support.sum() - len(union)) / n_points + k * (pa.kind.n_params + pb.kind.n_params - kind.n_params)
        if best is None or gain > best[0]:
            best = (gain, Piece(kind, tuple(float(v) for v in params), union[support]))
    return best


def _wall_meets_bore(params, pa: Piece, pb: Piece, vox) -> bool:
    """Would the cylinder join an outer wall to a bore? Its |cos| normal test cannot tell them apart."""
    a = shapes.faces_outward(params, vox.points[pa.members], vox.normals[pa.members]).mean()
    b = shapes.faces_outward(params, vox.points[pb.members], vox.normals[pb.members]).mean()
    return (a - 0.5) * (b - 0.5) < 0 and abs(a - b) > 0.5


def merge_greedy(pieces, labels, vox, edges, threshold, cos_max, max_gap, k, max_radius=np.inf):
    """Merge pieces in place while the MDL fitness improves.

    Args:
        pieces: dict id -> Piece; `labels` (M,) holds those ids, or -1.
        edges: (edge_i, edge_j, edge_len) of the neighbour graph.
    Returns the number of merges made.
    """
    n_points = len(labels)
    cache: dict[tuple[int, int], tuple | None] = {}
    merges = 0
    while True:
        best_pair, best = None, None
        for pair in adjacent_pairs(labels, *edges, max_gap):
            if pair not in cache:
                cache[pair] = _best_merge(pieces[pair[0]], pieces[pair[1]], vox, threshold, cos_max, n_points, k,
                                          max_radius)
            cand = cache[pair]
            if cand is not None and cand[0] > 0 and (best is None or cand[0] > best[0]):
                best_pair, best = pair, cand
        if best is None:
            return merges
        a, b = best_pair
        labels[pieces[a].members] = -1
        labels[pieces[b].members] = -1
        pieces[a] = best[1]
        labels[best[1].members] = a
        del pieces[b]
        cache = {pair: v for pair, v in cache.items() if a not in pair and b not in pair}
        merges += 1
