"""What no detection explains: the points standing on the table that lie on no detected part.

After a first search, a part that the coarse decomposition cut badly (a 54 mm bushing spans seven
8 mm voxels) or that other parts crowded out still shows as points above the table that no
detection accounts for. They are what a second, finer look is spent on.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.ndimage import label

from psorr.support_crop import along_plane
from psorr.types import PointCloud


def on_detected_surface(points: np.ndarray, detection, model_trees: dict, reach: float) -> np.ndarray:
    """(N,) bool: which of ``points`` (N, 3), cloud frame, lie within ``reach`` metres of the surface samples
    of ``detection``'s model at its pose (``model_trees``: name -> cKDTree of the samples, model frame)."""
    T_model_cloud = np.linalg.inv(detection.T_cloud_model)
    local = points @ T_model_cloud[:3, :3].T + T_model_cloud[:3, 3]
    gap, _ = model_trees[detection.model].query(local, distance_upper_bound=reach)
    return np.isfinite(gap)


def standing_points(cloud: PointCloud, plane: np.ndarray | None, off_plane: float) -> np.ndarray:
    """(N,) bool over ``cloud``'s points: finite, and more than ``off_plane`` metres above the supporting
    ``plane`` (a, b, c, d; the sensor on its positive side); every finite point when there is no plane."""
    points = cloud.points
    finite = cloud.valid_mask
    standing = finite.copy()
    if plane is not None:
        standing[finite] = points[finite] @ np.asarray(plane[:3]) + plane[3] > off_plane
    return standing


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
    metres along the plane, 8-connected) that could be one part: no higher above the ``plane`` and no
    wider along it than ``largest`` metres. An arm reaching across the table is neither."""
    if plane is None or not mask.any():
        return mask
    along, height = along_plane(cloud.points[mask], plane)
    cells = np.floor((along - along.min(axis=0)) / cell).astype(np.int64)
    grid = np.zeros(cells.max(axis=0) + 1, dtype=bool)
    grid[cells[:, 0], cells[:, 1]] = True
    groups, n = label(grid, structure=np.ones((3, 3)))
    group = groups[cells[:, 0], cells[:, 1]]
    keep = np.zeros(n + 1, dtype=bool)
    for g in range(1, n + 1):
        mine = group == g
        wide = np.linalg.norm(np.ptp(along[mine], axis=0))
        keep[g] = wide <= largest and height[mine].max() <= largest
    out = mask.copy()
    out[np.flatnonzero(mask)[~keep[group]]] = False
    return out


def blanked(cloud: PointCloud, mask: np.ndarray) -> PointCloud:
    """``cloud`` with the points under ``mask`` (N,) made NaN (point order kept, so labels computed on
    the result index ``cloud``)."""
    if not mask.any():
        return cloud
    out = cloud.points.copy()
    out[mask] = np.nan
    return replace(cloud, points=out)
