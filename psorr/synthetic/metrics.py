"""Scores of a decomposition against ground-truth object labels.

The table dominates a table-top cloud, so whole-cloud figures flatter any
plane-removal loop; these score each labelled object once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.errors import InvalidInputError


@dataclass(frozen=True)
class SegmentationScores:
    """coverage: mean over objects of the share of the object's points lying in
    primitives whose majority label is that object. purity: over the primitives
    whose majority is an object, the share of their points that belong to it.
    n_objects and n_object_primitives count what the means run over."""

    coverage: float
    purity: float
    n_objects: int
    n_object_primitives: int


def segmentation_scores(truth: np.ndarray, labels: np.ndarray, background=(0,)) -> SegmentationScores:
    """Score predicted labels (N,) (primitive index, -1 for none) against truth (N,).

    Args:
        truth: (N,) int object id per point; values in `background` (and below 0)
            are not objects (the table, invalid points) but still count as
            wrong points inside an object's primitive.
    """
    truth, labels = np.asarray(truth), np.asarray(labels)
    if truth.shape != labels.shape or truth.ndim != 1:
        raise InvalidInputError(f"truth and labels must both be (N,), got {truth.shape} and {labels.shape}")
    is_object = (truth >= 0) & ~np.isin(truth, background)
    assigned = labels >= 0
    # Contingency of primitive x truth value, via one bincount over pairs.
    t_vals, t_idx = np.unique(truth, return_inverse=True)
    n_prims = int(labels.max()) + 1 if assigned.any() else 0
    table = np.bincount(labels[assigned] * len(t_vals) + t_idx[assigned],
                        minlength=n_prims * len(t_vals)).reshape(n_prims, len(t_vals))
    sizes = table.sum(axis=1)
    majority = t_vals[np.argmax(table, axis=1)] if n_prims else np.array([], dtype=truth.dtype)
    objects = np.unique(truth[is_object])
    coverage = []
    for obj in objects:
        mine = np.flatnonzero((majority == obj) & (sizes > 0))
        col = np.searchsorted(t_vals, obj)
        coverage.append(table[mine, col].sum() / (truth == obj).sum())
    object_prims = np.flatnonzero(np.isin(majority, objects) & (sizes > 0))
    hits = table[object_prims, np.searchsorted(t_vals, majority[object_prims])].sum()
    purity = hits / sizes[object_prims].sum() if len(object_prims) else float("nan")
    return SegmentationScores(float(np.mean(coverage)) if coverage else float("nan"), float(purity),
                              len(objects), len(object_prims))


def osd_object_ids(labels: np.ndarray) -> np.ndarray:
    """Object Segmentation Database labels -> object ids: 0 for invalid points,
    1 for the table (labels 1-9), label // 10 for the objects (2, 3, ...)."""
    labels = np.asarray(labels)
    return np.where(labels >= 10, labels // 10, np.where(labels >= 1, 1, 0))


@dataclass(frozen=True)
class ObjectSegmentScore:
    """One labelled object against a segmentation: iou with its best-matching segment; over: a second
    segment holds at least a tenth of it; under: its best segment draws at least a tenth of its points
    from other objects or the background."""

    object_id: int
    iou: float
    over: bool
    under: bool


def object_segment_scores(truth: np.ndarray, labels: np.ndarray, background=(0, 1),
                          share: float = 0.1) -> list[ObjectSegmentScore]:
    """Score segments labels (N,) (-1 for none) against truth object ids (N,); ``background`` ids are
    not objects."""
    truth, labels = np.asarray(truth), np.asarray(labels)
    if truth.shape != labels.shape or truth.ndim != 1:
        raise InvalidInputError(f"truth and labels must both be (N,), got {truth.shape} and {labels.shape}")
    n_segments = int(labels.max()) + 1 if (labels >= 0).any() else 0
    seg_sizes = np.bincount(labels[labels >= 0], minlength=n_segments)
    scores = []
    for obj in np.unique(truth[(truth >= 0) & ~np.isin(truth, background)]):
        mine = truth == obj
        overlap = np.bincount(labels[mine & (labels >= 0)], minlength=n_segments)
        if n_segments == 0 or overlap.max() == 0:
            scores.append(ObjectSegmentScore(int(obj), 0.0, False, False))
            continue
        best = int(np.argmax(overlap / (mine.sum() + seg_sizes - overlap)))
        iou = overlap[best] / (mine.sum() + seg_sizes[best] - overlap[best])
        over = np.sort(overlap)[-2] >= share * mine.sum() if n_segments > 1 else False
        under = seg_sizes[best] - overlap[best] >= share * seg_sizes[best]
        scores.append(ObjectSegmentScore(int(obj), float(iou), bool(over), bool(under)))
    return scores
