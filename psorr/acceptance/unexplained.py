"""What no detection explains: the points standing on the table that lie on no detected part.

After a first search, a part that the coarse decomposition cut badly (a 54 mm bushing spans seven
8 mm voxels) or that other parts crowded out still shows as points above the table that no
detection accounts for. They are what a second, finer look is spent on.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from psorr.decomposition.support_crop import SupportCropParams, along_plane, standing_points
from psorr.types import PointCloud


class DetectedSurfaces:
    """The library's models' surface samples (``models``: those of a ModelLibrary), for asking which points
    the detections so far explain: those within ``reach`` metres of a detected model's samples at its pose.
    A point stands on the supporting plane as the support crop's ``standing`` params say
    (:func:`~psorr.decomposition.support_crop.standing_bar`); a group of standing points wider or higher than
    ``largest`` metres is no part, and fewer than ``min_points`` left standing are none."""

    def __init__(self, models, reach: float, standing: SupportCropParams, largest: float, min_points: int):
        self.trees = {m.name: cKDTree(m.points) for m in models}
        self.reach, self.standing, self.largest, self.min_points = reach, standing, largest, min_points

    def explain(self, detections, points: np.ndarray, share: float = 0.5) -> bool:
        """Does at least ``share`` of ``points`` (M, 3), a primitive's, lie on the surface of one of
        ``detections``? The whole surface, not the pixels it covers: a part's far side in a full view is
        explained too, and a part behind a detected one is not."""
        points = points[:: max(1, len(points) // 200)]
        return any(on_detected_surface(points, d, self.trees, self.reach).mean() >= share for d in detections)

    def unexplained(self, cloud: PointCloud, plane: np.ndarray | None, detections) -> PointCloud | None:
        """``cloud`` with the points standing on the supporting ``plane`` blanked where ``detections`` explain
        them, or where they form groups too large to be one part (:func:`part_sized`); None when too few stand
        unexplained. What stands is the same in a cloud as in its crop (the crop keeps every standing point),
        so the answer is too."""
        standing = standing_points(cloud, plane, self.standing)
        rest = standing_unexplained(cloud, standing, detections, self.trees, self.reach)
        rest = part_sized(cloud, plane, rest, self.largest)
        if rest.sum() < self.min_points:
            return None
        return blanked(cloud, standing & ~rest)


def on_detected_surface(points: np.ndarray, detection, model_trees: dict, reach: float) -> np.ndarray:
    """(N,) bool: which of ``points`` (N, 3), cloud frame, lie within ``reach`` metres of the surface samples
    of ``detection``'s model at its pose (``model_trees``: name -> cKDTree of the samples, model frame)."""
    T_model_cloud = np.linalg.inv(detection.T_cloud_model)
    local = points @ T_model_cloud[:3, :3].T + T_model_cloud[:3, 3]
    gap, _ = model_trees[detection.model].query(local, distance_upper_bound=reach)
    return np.isfinite(gap)


def standing_unexplained(cloud: PointCloud, standing: np.ndarray, detections, model_trees: dict,
                         reach: float) -> np.ndarray:
    """(N,) bool: the ``standing`` points of ``cloud`` (see :func:`standing_points`) farther than ``reach``
    metres from the surface samples of every detection's model (``model_trees``: name -> cKDTree of the
    samples, model frame)."""
    pts = cloud.points
    mask = standing.copy()
    for d in detections:
        index = np.flatnonzero(mask)
        if len(index) == 0:
            break
        mask[index[on_detected_surface(pts[index], d, model_trees, reach)]] = False
    return mask


def part_sized(cloud: PointCloud, plane: np.ndarray | None, mask: np.ndarray, largest: float,
               cell: float = 0.01) -> np.ndarray:
    """``mask`` (N,) bool over ``cloud``'s points, keeping only the connected groups (cells of ``cell``
    metres along the plane and in height, 26-connected) that could be one part: no higher above the
    ``plane`` and no wider along it than ``largest`` metres. An arm reaching across the table is neither.

    Connected in height too, not only along the plane: an arm held over a part covers it in a view
    from above, and grouped by their footprints the two were one group, too wide, and the part went
    with the arm (a circuit board 79% in view, its components below a forearm, never had its second look).
    """
    if plane is None or not mask.any():
        return mask
    along, height = along_plane(cloud.points[mask], plane)
    group = _connected_cells(np.floor(np.column_stack([along, height]) / cell).astype(np.int64))
    n = group.max() + 1
    low, high, top = np.full((n, 2), np.inf), np.full((n, 2), -np.inf), np.full(n, -np.inf)
    np.minimum.at(low, group, along)
    np.maximum.at(high, group, along)
    np.maximum.at(top, group, height)
    wide = (np.linalg.norm(high - low, axis=1) > largest) | (top > largest)
    out = mask.copy()
    out[np.flatnonzero(mask)[wide[group]]] = False
    return out


def _connected_cells(cells: np.ndarray) -> np.ndarray:
    """(N,) group of each of the (N, 3) integer cells, 26-connected. Only occupied cells are numbered
    (a dense grid over a cloud several metres deep would take gigabytes); neighbours are found by key."""
    cells = cells - cells.min(axis=0) + 1  # a margin of one empty cell, so no neighbour's key wraps around
    dims = cells.max(axis=0) + 2
    keys, cell_of = np.unique((cells[:, 0] * dims[1] + cells[:, 1]) * dims[2] + cells[:, 2], return_inverse=True)
    steps = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)])
    steps = steps[:13]  # one of each pair of opposite neighbours: edges are undirected
    first, second = [], []
    for di, dj, dk in steps:
        neighbour = keys + (di * dims[1] + dj) * dims[2] + dk
        at = np.minimum(np.searchsorted(keys, neighbour), len(keys) - 1)
        hit = keys[at] == neighbour
        first.append(np.flatnonzero(hit))
        second.append(at[hit])
    first, second = np.concatenate(first), np.concatenate(second)
    n = len(keys)
    graph = coo_matrix((np.ones(len(first), dtype=np.int8), (first, second)), shape=(n, n))
    return connected_components(graph, directed=False)[1][cell_of.ravel()]


def blanked(cloud: PointCloud, mask: np.ndarray) -> PointCloud:
    """``cloud`` with the points under ``mask`` (N,) made NaN (point order kept, so labels computed on
    the result index ``cloud``)."""
    if not mask.any():
        return cloud
    out = cloud.points.copy()
    out[mask] = np.nan
    return replace(cloud, points=out)
