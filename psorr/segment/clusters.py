"""Conditional Euclidean clustering (after PCL's ConditionalEuclideanClustering): points join one
cluster when they are neighbours within a distance and a condition on the pair holds, here that
their colour labels agree."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components


def conditional_clusters(n: int, edge_i: np.ndarray, edge_j: np.ndarray, joined: np.ndarray) -> np.ndarray:
    """(n,) cluster ids: connected components of the graph of the edges (E,) with ``joined`` (E,) True."""
    graph = coo_matrix((np.ones(int(joined.sum())), (edge_i[joined], edge_j[joined])), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def absorb_small(clusters: np.ndarray, edge_i: np.ndarray, edge_j: np.ndarray, near: np.ndarray,
                 min_size: int) -> np.ndarray:
    """Clusters (N,) with every one under ``min_size`` members given to the large cluster it shares most
    ``near`` (E,) edges with (colour aside: a few voxels of shading or a printed label on a part), or -1
    when it touches none. Large clusters renumbered 0..K-1 by size."""
    sizes = np.bincount(clusters)
    large = sizes >= min_size
    a, b = clusters[edge_i[near]], clusters[edge_j[near]]
    small_to_large = np.r_[np.column_stack([a, b])[~large[a] & large[b]],
                           np.column_stack([b, a])[~large[b] & large[a]]]
    target = np.full(len(sizes), -1, dtype=np.int64)
    target[large] = np.flatnonzero(large)
    if len(small_to_large):
        pairs, contacts = np.unique(small_to_large, axis=0, return_counts=True)
        order = np.lexsort((-contacts, pairs[:, 0]))  # per small cluster, the most contacts first
        pairs = pairs[order]
        first = np.r_[True, pairs[1:, 0] != pairs[:-1, 0]]
        target[pairs[first, 0]] = pairs[first, 1]
    return by_size(target[clusters])


def by_size(clusters: np.ndarray) -> np.ndarray:
    """Cluster ids (N,) (-1: none) renumbered 0..K-1, largest first (ties in id order)."""
    kept = np.unique(clusters[clusters >= 0])
    order = kept[np.argsort(-np.bincount(clusters[clusters >= 0])[kept], kind="stable")]
    renumber = np.full(int(clusters.max(initial=-1)) + 1, -1, dtype=np.int64)
    renumber[order] = np.arange(len(order))
    return np.where(clusters >= 0, renumber[np.maximum(clusters, 0)], -1)


def merge_unless_distinct(clusters: np.ndarray, colours: np.ndarray, edge_i: np.ndarray, edge_j: np.ndarray,
                          near: np.ndarray, spread: float, distance: float) -> np.ndarray:
    """Touching clusters (N,) joined unless both are evenly coloured (the spread of their members'
    colours (N, 3) under ``spread``) and their mean colours lie ``distance`` or more apart: a printed
    box splits into colour patches that are not parts. Returns clusters renumbered by size."""
    valid = clusters >= 0
    n = int(clusters.max()) + 1 if valid.any() else 0
    if n < 2:
        return clusters
    counts = np.bincount(clusters[valid], minlength=n)[:, None]
    means = np.column_stack([np.bincount(clusters[valid], colours[valid, k], n) for k in range(3)]) / counts
    square = np.column_stack([np.bincount(clusters[valid], colours[valid, k] ** 2, n) for k in range(3)]) / counts
    even = np.sqrt(np.maximum(square - means**2, 0.0).sum(axis=1)) < spread
    a, b = clusters[edge_i[near]], clusters[edge_j[near]]
    touching = (a >= 0) & (b >= 0) & (a != b)
    a, b = a[touching], b[touching]
    distinct = even[a] & even[b] & (np.linalg.norm(means[a] - means[b], axis=1) >= distance)
    joined = conditional_clusters(n, a, b, ~distinct)
    return by_size(np.where(valid, joined[np.maximum(clusters, 0)], -1))
