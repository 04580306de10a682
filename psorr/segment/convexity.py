"""Concave creases between voxels (the convexity test of LCCP, Stein et al. 2014): where two objects
touch, their surfaces meet in a concave crease, while an object's own surface is convex or smoothly
bent. Voxels on a crease are set aside as seeds, so that no chain of them bridges two objects, and
join a cluster afterwards."""

from __future__ import annotations

import numpy as np

from psorr.segment.clusters import by_size, conditional_clusters


def median_bend(normals: np.ndarray, edge_i: np.ndarray, edge_j: np.ndarray) -> float:
    """The median angle (radians) between the normals (N, 3) at the two ends of the edges (E,)."""
    return float(np.median(_bend(normals, edge_i, edge_j)))


def _bend(normals: np.ndarray, edge_i: np.ndarray, edge_j: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(np.sum(normals[edge_i] * normals[edge_j], axis=1), -1.0, 1.0))


def concave_edges(centroids: np.ndarray, normals: np.ndarray, edge_i: np.ndarray, edge_j: np.ndarray,
                  min_bend: float) -> np.ndarray:
    """(E,) True where the surface folds inwards between voxels i and j by more than ``min_bend``
    radians: the normals turn towards each other, (n_i - n_j) . (x_i - x_j) < 0."""
    offset = centroids[edge_i] - centroids[edge_j]
    inwards = np.sum((normals[edge_i] - normals[edge_j]) * offset, axis=1) < 0
    return inwards & (_bend(normals, edge_i, edge_j) > min_bend)


def crease_voxels(n: int, edge_i: np.ndarray, edge_j: np.ndarray, concave: np.ndarray) -> np.ndarray:
    """(n,) True for the voxels at either end of a concave edge."""
    out = np.zeros(n, dtype=bool)
    out[edge_i[concave]] = True
    out[edge_j[concave]] = True
    return out


def grow_into(clusters: np.ndarray, edge_i: np.ndarray, edge_j: np.ndarray, open_: np.ndarray) -> np.ndarray:
    """Clusters (N,) with every ``open_`` (N,) voxel given, ring by ring outwards from the clusters, the
    cluster most of its already labelled neighbours (edges (E,), (E,)) hold. A voxel no ring reaches
    keeps -1."""
    labels = np.where(open_, -1, clusters)
    source, target = np.r_[edge_i, edge_j], np.r_[edge_j, edge_i]
    while True:
        take = (labels[target] < 0) & (labels[source] >= 0)
        if not take.any():
            return labels
        votes, counts = np.unique(np.column_stack([target[take], labels[source[take]]]), axis=0,
                                  return_counts=True)
        order = np.lexsort((-counts, votes[:, 0]))
        votes = votes[order]
        first = np.r_[True, votes[1:, 0] != votes[:-1, 0]]
        labels[votes[first, 0]] = votes[first, 1]


def join_unless_concave(parts: np.ndarray, edge_i: np.ndarray, edge_j: np.ndarray,
                        concave: np.ndarray) -> np.ndarray:
    """Parts (N,) (-1: none) joined pairwise unless at least half the edges (E,) between two of them
    are ``concave`` (E,): where objects touch, most of the contact is a crease, while a thin rim or a
    few noisy normals cut one surface along a line that mostly is not. Renumbered by size."""
    a, b = parts[edge_i], parts[edge_j]
    across = (a != b) & (a >= 0) & (b >= 0)
    pairs, inverse = np.unique(np.column_stack([np.minimum(a, b), np.maximum(a, b)])[across], axis=0,
                               return_inverse=True)
    inverse = inverse.ravel()
    folded = np.bincount(inverse, concave[across], len(pairs)) / np.maximum(np.bincount(inverse, None, len(pairs)), 1)
    joined = pairs[folded < 0.5]
    components = conditional_clusters(int(parts.max(initial=-1)) + 1, joined[:, 0], joined[:, 1],
                                      np.ones(len(joined), dtype=bool))
    return by_size(np.where(parts >= 0, components[np.maximum(parts, 0)], -1))
