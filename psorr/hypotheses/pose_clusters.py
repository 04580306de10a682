"""Clustering of pair-vote poses: the best-supported poses of each model, one per cluster.

Every matched pair votes for a pose. Poses of a true instance scatter by a
centimetre and several degrees, as scene centroids are seldom where model
samples were drawn, and a single grid over position and rotation splits such
a cloud of votes across its cell borders (a bracket's 11 good votes fell into
5 cells, none among the model's top 12). So votes are counted on two grids,
the second shifted by half a cell along every axis: a cluster that straddles
a border of one sits inside a cell of the other. Each pose scores the fuller
of its two cells.

A grid cell spans ``cell`` metres of the model centre's position and a
quarter in each component of the rotation's quaternion (about 30 degrees).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation


def _coordinates(poses: np.ndarray, centres: np.ndarray, cell: float) -> np.ndarray:
    """(K, 7) grid coordinates (in cells) of poses: the model centre's position, and the quaternion."""
    where = np.einsum("kij,kj->ki", poses[:, :3, :3], centres) + poses[:, :3, 3]
    quat = Rotation.from_matrix(poses[:, :3, :3]).as_quat()
    quat *= np.where(quat[:, 3:] < 0, -1, 1)  # q and -q are one rotation
    return np.column_stack([where / cell, quat * 4])


def _cell_keys(models: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """(K,) one int64 per (model, 7 cell coordinates): 14 bits of model, 10 per position cell (cells
    wrap every 1024, 20 m at 2 cm: far beyond a sensor's range) and 4 per quaternion cell (-4..4)."""
    key = models.astype(np.int64)
    for column, bits in zip(cells.T, (10, 10, 10, 4, 4, 4, 4)):
        key = (key << bits) | (column & ((1 << bits) - 1))
    return key


def densest_poses(poses: np.ndarray, models: np.ndarray, voters: np.ndarray, centres: np.ndarray, cell: float,
                  limit: int, least_per_model: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """About ``limit`` poses, an equal share per model (never fewer than ``least_per_model`` a model),
    best-supported first and one per cell.

    poses (K, 4, 4) T_cloud_model; models (K,) indices into centres (M, 3), each model's centre in
    its own frame; voters (K,) int, the scene pair each pose came from (a cell's support is the
    number of distinct scene pairs in it); cell in metres. An equal share, because a model with many primitives collects
    more chance votes, and a single ranking would crowd the others out. A pose is taken only if
    neither of its cells gave a pose already, so each cluster yields one hypothesis. The floor keeps a
    model's share from shrinking as the library grows: a part whose true cluster ranks third by votes
    must still be posed in a library of 40 (docs/decisions/0015).
    Returns the chosen poses and their models.
    """
    best = densest(poses, models, voters, centres, cell, limit, least_per_model)
    return poses[best], models[best]


def densest(poses: np.ndarray, models: np.ndarray, voters: np.ndarray, centres: np.ndarray, cell: float,
            limit: int, least_per_model: int = 1) -> np.ndarray:
    """The indices (into poses (K, 4, 4)) that densest_poses chooses."""
    if len(poses) == 0:
        return np.zeros(0, dtype=np.int64)
    coords = _coordinates(poses, centres[models], cell)
    cells, votes = [], []
    voters = np.asarray(voters, dtype=np.int64)
    n_voters = int(voters.max()) + 1
    for shift in (0.0, 0.5):
        _, cell_of = np.unique(_cell_keys(models, np.floor(coords + shift).astype(np.int64)), return_inverse=True)
        # One vote per scene pair and cell: a pair of parallel faces matches hundreds of model pairs
        # that all give nearly the same pose, and would outvote an instance that many pairs agree on.
        ballots = np.unique(cell_of * n_voters + voters) // n_voters
        count = np.bincount(ballots, minlength=cell_of.max() + 1)
        cells.append(cell_of)
        votes.append(count[cell_of])
    score = np.maximum(*votes)
    quota = max(1, least_per_model, limit // len(centres))
    chosen = []
    for model in np.unique(models):
        mine = np.flatnonzero(models == model)
        used: tuple[set, set] = (set(), set())
        picked = []
        for k in mine[np.argsort(-score[mine], kind="stable")]:
            a, b = int(cells[0][k]), int(cells[1][k])
            if a in used[0] or b in used[1]:
                continue
            used[0].add(a)
            used[1].add(b)
            picked.append(k)
            if len(picked) == quota:
                break
        chosen.append(np.array(picked, dtype=np.int64))
    return np.concatenate(chosen)


def share_out(order, models, limit):
    """Up to `limit` of the ranked hypotheses, taken round-robin across models
    so that one model's many near-duplicates cannot fill every slot."""
    queues = {}
    for k in order:
        queues.setdefault(int(models[k]), []).append(k)
    chosen = []
    while len(chosen) < limit and any(queues.values()):
        for queue in queues.values():
            if queue and len(chosen) < limit:
                chosen.append(queue.pop(0))
    return chosen


def same_pose(points: np.ndarray, A: np.ndarray, B: np.ndarray, tolerance: float) -> bool:
    """Do poses A and B (4, 4) place ``points`` (N, 3) within ``tolerance`` metres of each other, on average?"""
    return float(np.linalg.norm(points @ (A[:3, :3] - B[:3, :3]).T + (A[:3, 3] - B[:3, 3]), axis=1).mean()) < tolerance


def apart_from(found, detections, library):
    """The :class:`~psorr.hypotheses.candidates.CandidateSet` ``found`` less the candidates within a tenth of
    their model's diameter (the accuracy the benchmarks ask) of one of the ``detections`` of it, models of
    ``library``: ICP would take them to that detection, which keeps its pixels."""
    standing = [(library.names.index(d.model), d.T_cloud_model) for d in detections]
    new = tuple(c for c in found.candidates if not any(
        m == c.model and same_pose(library.models[m].points[::50], c.T_cloud_model, T, 0.1 * library.models[m].diameter)
        for m, T in standing))
    return replace(found, candidates=new)
