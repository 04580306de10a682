"""Colour labels by a multi-label graph cut: each voxel takes one of a few colour models (CIELAB
means), trading how far its colour lies from the model against its neighbours' labels. The cut is
the decomposition's alpha-expansion (psorr.decomposition.graphcut), with colour models for shapes."""

from __future__ import annotations

import numpy as np
from scipy.cluster.vq import kmeans2

from psorr.decomposition.graphcut import alpha_expansion


def weighted_lab(lab: np.ndarray, lightness_weight: float) -> np.ndarray:
    """(N, 3) CIELAB with its lightness scaled: shading moves L far more than a surface's hue."""
    return lab * np.array([lightness_weight, 1.0, 1.0])


def colour_models(colours: np.ndarray, max_models: int, merge_distance: float,
                  rng: np.random.Generator) -> np.ndarray:
    """(K, 3) model colours: k-means (k-means++ seeding) with up to ``max_models`` centres on ``colours``
    (N, 3), then the closest two merged while nearer than ``merge_distance``, weighted by their members."""
    k = min(max_models, len(np.unique(colours, axis=0)))
    if k <= 1:
        return colours.mean(axis=0, keepdims=True)
    centres, member = kmeans2(colours, k, minit="++", rng=rng)
    counts = np.bincount(member, minlength=k).astype(float)
    centres, counts = centres[counts > 0], counts[counts > 0]
    while len(centres) > 1:
        gaps = np.linalg.norm(centres[:, None] - centres[None], axis=2) + np.diag(np.full(len(centres), np.inf))
        a, b = np.unravel_index(np.argmin(gaps), gaps.shape)
        if gaps[a, b] >= merge_distance:
            break
        centres[a] = (counts[a] * centres[a] + counts[b] * centres[b]) / (counts[a] + counts[b])
        counts[a] += counts[b]
        centres, counts = np.delete(centres, b, axis=0), np.delete(counts, b)
    return centres


def colour_cut(colours: np.ndarray, edges: tuple[np.ndarray, np.ndarray], models: np.ndarray, sigma: float,
               smoothness: float, rng: np.random.Generator, rounds: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Labels (N,) into the colour models (K, 3), and the models refitted to their members.

    Data cost: squared distance to the model over 2 sigma^2. Potts weight between neighbours (edges:
    (E,) and (E,) voxel indices): ``smoothness`` times exp(-d^2 / 2 sigma^2) of their own colour
    distance d, so a border between colours is cheap to cut and one within a colour dear. The models
    are refitted and the cut run again ``rounds`` times in all (as GrabCut iterates)."""
    edge_i, edge_j = edges
    d2 = np.sum((colours[edge_i] - colours[edge_j]) ** 2, axis=1)
    weights = smoothness * np.exp(-d2 / (2 * sigma**2))
    labels = np.zeros(len(colours), dtype=np.int64)
    for _ in range(rounds):
        costs = np.sum((colours[:, None, :] - models[None]) ** 2, axis=2) / (2 * sigma**2)
        labels, _ = alpha_expansion(costs, edge_i, edge_j, weights, costs.argmin(axis=1), rng)
        used = np.unique(labels)
        models = np.array([colours[labels == m].mean(axis=0) for m in used])
        labels = np.searchsorted(used, labels)
    return labels, models
