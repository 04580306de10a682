"""Finer decompositions: of what the first one left unlabelled, and of what recognition left unexplained.

A voxel size that keeps a whole table top fast (8 mm) is too coarse for a
part's small faces: a circuit board's components, a bush's 10 mm flange ring
or a face cut down by a neighbour come out as a few voxels with mixed
normals, and no primitive. Those points are only a percent or so of the
cloud, so decomposing just them again at a finer voxel costs tens of
milliseconds and finds the faces.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from psorr.checks import params as check
from psorr.decomposition.pipeline import DecomposeParams, Decomposition, DecompositionStats, decompose
from psorr.decomposition.psg import close_pairs
from psorr.errors import InvalidInputError, TooSparseError
from psorr.types import PointCloud, PrimitiveShapeGraph

_EDGE_SAMPLES = 400  # inliers per primitive that decide the edges between the two passes' primitives


@dataclass(frozen=True)
class DetailParams:
    """The finer passes of recognition's decomposition; voxels in metres, None turns a pass off.

    ``leftover_voxel``: the points the first decomposition left unlabelled, decomposed again at this voxel.
    ``fine_voxel``: what stands on the table unexplained after the search, decomposed again at this voxel
    and searched again, if at least ``min_unexplained`` points (a detection needs acceptance's min_support),
    with a band of the table ``fine_band`` metres wide around it; the table is the plane that holds the
    band's outer cells (:func:`psorr.decomposition.support_crop.table_in_band`).
    """

    leftover_voxel: float | None = 0.005
    fine_voxel: float | None = 0.005
    min_unexplained: int = 100
    fine_band: float = 0.04

    def __post_init__(self):
        check.positive(self, "leftover_voxel", "fine_voxel", unit=" metres", optional=True)
        check.positive(self, "fine_band", unit=" metres")
        check.whole(self, "min_unexplained")


def decompose_with_leftovers(cloud: PointCloud, params: DecomposeParams, leftover_voxel: float | None,
                             rng: np.random.Generator) -> Decomposition | None:
    """``cloud`` decomposed, and its unlabelled points again at ``leftover_voxel`` metres (unless None); None
    when the cloud is too sparse to decompose (a handful of points, or a few clumps: nothing to find)."""
    try:
        scene = decompose(cloud, params, rng)
    except TooSparseError:
        return None
    if leftover_voxel is not None:
        scene = decompose_leftovers(cloud, scene, leftover_voxel, params, rng)
    return scene


def decompose_leftovers(cloud: PointCloud, coarse: Decomposition, voxel_size: float, params: DecomposeParams,
                        rng: np.random.Generator) -> Decomposition:
    """``coarse`` plus the primitives of its unlabelled points decomposed at ``voxel_size`` metres.

    The new primitives come after the coarse ones, with inliers indexing ``cloud``; labels and
    stats (times, voxels, hypotheses, merges) cover both passes. Edges join primitives of either
    pass whose inliers come within the coarse adjacency gap.
    """
    if not voxel_size > 0:
        raise InvalidInputError(f"the leftover pass needs a voxel size > 0 metres, got {voxel_size}")
    start = time.perf_counter()
    left = np.flatnonzero((coarse.labels < 0) & cloud.valid_mask)
    if len(left) < params.min_points:
        return coarse
    try:
        fine = decompose(PointCloud(cloud.points[left]), dataclasses.replace(params, voxel_size=voxel_size), rng)
    except TooSparseError:  # a few clumps of leftovers: no primitive among them
        return coarse
    if not fine.primitives:
        return coarse
    offset = len(coarse.primitives)
    primitives = coarse.primitives + tuple(dataclasses.replace(p, inliers=left[p.inliers]) for p in fine.primitives)
    labels = coarse.labels.copy()
    labelled = fine.labels >= 0
    labels[left[labelled]] = fine.labels[labelled] + offset
    edges = set(coarse.graph.edges) | {(i + offset, j + offset) for i, j in fine.graph.edges}
    edges |= _edges_between(cloud, primitives, offset, params.adjacency_gap * params.voxel_size)
    a, b = coarse.stats, fine.stats
    stats = DecompositionStats(a.total_ms + (time.perf_counter() - start) * 1e3, a.preprocess_ms + b.preprocess_ms,
                               a.hypotheses_ms + b.hypotheses_ms, a.graphcut_ms + b.graphcut_ms,
                               a.merge_ms + b.merge_ms, a.n_voxels + b.n_voxels, a.n_hypotheses + b.n_hypotheses,
                               a.n_merges + b.n_merges, a.n_sampled)
    return Decomposition(PrimitiveShapeGraph(primitives, tuple(edges)), labels, stats)


def _edges_between(cloud, primitives, offset, gap) -> set[tuple[int, int]]:
    """Edges from a coarse primitive (index < offset) to a fine one, by evenly strided inliers."""
    owner, points = [], []
    for index, p in enumerate(primitives):
        sample = p.inliers[:: max(1, len(p.inliers) // _EDGE_SAMPLES)]
        owner.append(np.full(len(sample), index))
        points.append(cloud.points[sample])
    pairs = close_pairs(np.concatenate(owner), np.vstack(points), gap)
    return {(i, j) for i, j in pairs if i < offset <= j}
