"""Patches of points standing on a supporting plane: what the resting-pose search poses parts over.

The standing points are gridded on the table in cells; the raised cells, closed and opened, are labelled into
connected patches (:class:`StandingGrid`). Which points stand, and which patches count, is the
:class:`~psorr.hypotheses.outline.OutlineParams`' business; the grid only keeps what the searches need.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.special import log_ndtr

from psorr.geometry.boxes import orthonormal_frame
from psorr.geometry.distance_field import DistanceField
from psorr.geometry.grid_morphology import closing, opening
from psorr.sensing.noise_context import depth_noise
from psorr.types import PointCloud
from psorr.verification.point_check import CheckParams, depth_tolerance

# Percent: a patch's top and reach are those of all but its 2% most extreme points. The table's noise lifts
# specks of it above the standing bar, and the closing joins those beside a part to its patch: an extruder
# body's patch reached 70 mm from its centre, 16 mm past the part, by specks of table (its 99th percentile, 51).
EXTREME_SHARE = 98


@dataclass(frozen=True, eq=False)
class Patch:
    """Points standing on the table, connected: ``points`` (N, 3) in the table frame, ``outside`` the
    distance field of the cells a silhouette may cover at no cost (2-D), ``tolerance`` the depth tolerance
    at its median depth; ``bar`` the height (m) a point had to stand above the table, and ``height_sigma``
    the sensor's noise across the table (m), both at its median depth."""

    points: np.ndarray
    outside: DistanceField
    tolerance: float
    bar: float = 0.0
    height_sigma: float = 0.0

    def lift(self, height: float) -> float:
        """How far (m) above a face ``height`` m over the table its standing points lie on average: only those
        the noise lifts past the bar stand, the mean of a normal cut at the bar (a 3.5 mm plate 1 m away, bar
        4.2 mm, 2.1 mm of noise: 2.1 mm; a face two sigmas over the bar: 0.1 sigma)."""
        if self.height_sigma <= 0:
            return 0.0
        a = (self.bar - height) / self.height_sigma
        # The normal's density over its tail beyond a, in logs: scipy.stats.norm's logpdf - logsf, to the bit,
        # without its 70 microseconds a call (a call per resting shape searched).
        return float(self.height_sigma * np.exp(-0.5 * a * a - 0.5 * np.log(2.0 * np.pi) - log_ndtr(-a)))


def patch_reach(patch: Patch) -> float:
    """How far ``patch`` reaches from its centre on the table: all but its most extreme points."""
    centre = patch.points[:, :2].mean(axis=0)
    return float(np.percentile(np.linalg.norm(patch.points[:, :2] - centre, axis=1), EXTREME_SHARE))


def reaching(shifts: np.ndarray, points: np.ndarray, radius: float) -> np.ndarray:
    """(S,) whether all but the most extreme of ``points`` (N, 3) lie within ``radius`` of each of ``shifts``
    (S, 3) on the table."""
    apart = np.linalg.norm(points[None, :, :2] - shifts[:, None, :2], axis=2)
    return np.percentile(apart, EXTREME_SHARE, axis=1) <= radius


def table_frame(plane: np.ndarray) -> np.ndarray:
    """T_cloud_table (4, 4) of a supporting plane (a, b, c, d; unit normal towards the sensor): z along the
    normal, the origin the plane's point nearest the sensor."""
    normal = np.asarray(plane[:3], dtype=float)
    T = np.eye(4)
    T[:3, 0], T[:3, 1] = orthonormal_frame(normal)
    T[:3, 2], T[:3, 3] = normal, -plane[3] * normal
    return T


def flat_cells(points: np.ndarray, T_table_cloud: np.ndarray, low: np.ndarray, cell: float,
               shape: tuple) -> tuple[np.ndarray, np.ndarray]:
    """The flat index (N,) into a grid of ``shape`` cells of ``cell`` from ``low`` (2,) on the table of each of
    ``points`` (N, 3), and (N,) whether it falls on the grid (the index of one that does not is meaningless)."""
    # Column by column: (N, 2) arrays and their reductions over axis 1 took twice as long on 300,000 points.
    rows = np.floor((points @ T_table_cloud[0, :3] + T_table_cloud[0, 3] - low[0]) / cell).astype(np.int64)
    cols = np.floor((points @ T_table_cloud[1, :3] + T_table_cloud[1, 3] - low[1]) / cell).astype(np.int64)
    inside = (rows >= 0) & (rows < shape[0]) & (cols >= 0) & (cols < shape[1])
    return rows * shape[1] + cols, inside


@dataclass(frozen=True, eq=False)
class StandingGrid:
    """The standing points' grid on the table: ``points`` (N, 3) in the table frame and their ``depth`` (N,;
    metres from the sensor); ``labels`` (rows, cols) the patch of each cell (0: none), ``owner`` (N,) each
    point's; ``patches`` the labels that count as parts' patches; cell ``k``'s centre lies at
    ``low + (k + 0.5) cell``. ``T_cloud_table`` (4, 4) is the table's frame. A point stood when higher than
    ``sigmas`` x the depth sigma at its depth, and than ``min_height`` (m)."""

    points: np.ndarray
    depth: np.ndarray
    labels: np.ndarray
    owner: np.ndarray
    patches: tuple[int, ...]
    low: np.ndarray
    cell: float
    T_cloud_table: np.ndarray
    sigmas: float = 0.0
    min_height: float = 0.0

    def centres(self, cells: np.ndarray) -> np.ndarray:
        """(K, 2) the table coordinates of the ``cells`` (rows, cols) mask's cells."""
        return np.argwhere(cells) * self.cell + self.low + self.cell / 2

    def patch(self, label: int, free: np.ndarray, truncation: float, check: CheckParams,
              members: np.ndarray | None = None) -> Patch:
        """Patch ``label``'s points (or the points ``members`` (N,) marks), with the ``free`` cells (rows, cols)
        as those its silhouette may cover."""
        members = self.owner == label if members is None else members
        outside = DistanceField.of_points(self.centres(free), self.cell, truncation)
        depth = float(np.median(self.depth[members]))
        sigma = float(depth_noise().depth_sigma(np.array([depth]))[0])
        # A depth error moves a point along its ray: its height by the error times the sensor's height over the depth.
        over_table = self.T_cloud_table[:3, 3] @ self.T_cloud_table[:3, 2]
        return Patch(self.points[members], outside, float(depth_tolerance(depth, check)),
                     max(self.min_height, self.sigmas * sigma), sigma * abs(over_table) / depth)

    def cores(self, label: int, min_area: float) -> list[tuple[np.ndarray, np.ndarray]]:
        """Patch ``label`` split where only the closing joined it: (points (N,) mask, cells (rows, cols) mask) of
        each piece its raised cells make without the closing, at least ``min_area`` (m^2) each, the patch's other
        cells and points going to the nearest piece; [] when it makes fewer than two."""
        whole = self.labels == label
        raised = np.zeros_like(whole)
        members = np.flatnonzero(self.owner == label)
        cells, _ = flat_cells(self.points[members], np.eye(4), self.low, self.cell, whole.shape)
        raised.ravel()[cells] = True
        pieces, count = ndimage.label(opening(raised & whole))
        area = np.bincount(pieces.ravel(), minlength=count + 1) * self.cell**2
        big = [k for k in range(1, count + 1) if area[k] >= min_area]
        if len(big) < 2:
            return []
        cores = np.where(np.isin(pieces, big), pieces, 0)
        nearest = ndimage.distance_transform_edt(cores == 0, return_distances=False, return_indices=True)
        owner = cores[tuple(nearest)]  # each cell's nearest piece
        of_point = owner.ravel()[cells]
        out = []
        for k in big:
            points = np.zeros(len(self.points), dtype=bool)
            points[members[of_point == k]] = True
            out.append((points, whole & (owner == k)))
        return out


def standing_grid(cloud: PointCloud, plane: np.ndarray, params, tallest: float, check: CheckParams,
                  margin: float = 0.0) -> StandingGrid | None:
    """The grid of ``cloud``'s points standing on ``plane`` (see OutlineParams: ``params``), no higher than
    ``tallest`` metres, with ``margin`` metres of table around them; None when fewer than three stand."""
    p = params
    points = cloud.points[cloud.valid_mask]
    height = points @ plane[:3] + plane[3]
    # The sensor's sigma only where the floor is cleared: a tenth of the points on a noisy table.
    standing = height > p.min_height
    standing[standing] = height[standing] > p.sigmas * depth_noise().depth_sigma(points[standing, 2])
    # Higher than any resting model reaches, a point is something else's (an arm reaching in): it neither
    # joins a patch nor counts among its cells' points, or a part under the arm would join the arm's patch.
    # The tolerance is looked up only for the few points above the tallest rest, not the whole image.
    beyond = height > tallest
    beyond[beyond] = height[beyond] > tallest + depth_tolerance(points[beyond, 2], check)
    standing &= ~beyond
    if standing.sum() < 3:
        return None
    T_cloud_table = table_frame(plane)
    T_table_cloud = np.linalg.inv(T_cloud_table)
    up = points[standing] @ T_table_cloud[:3, :3].T + T_table_cloud[:3, 3]
    low = up[:, :2].min(axis=0) - margin - p.cell
    shape = tuple(np.floor((up[:, :2].max(axis=0) + margin + p.cell - low) / p.cell).astype(np.int64) + 1)
    where, inside = flat_cells(points, T_table_cloud, low, p.cell, shape)
    inside &= ~beyond
    every = np.bincount(where[inside], minlength=np.prod(shape))
    raised = np.bincount(where[standing], minlength=np.prod(shape))
    labels, count = ndimage.label(opening(closing(raised.reshape(shape) > 0, iterations=2)))
    # Per label at once: the table's noise raises hundreds of specks, each a pass over the grid otherwise.
    flat = labels.ravel()
    area = np.bincount(flat, minlength=count + 1)
    raised_in, every_in = (np.bincount(flat, weights=c, minlength=count + 1) for c in (raised, every))
    counted = tuple(k for k in range(1, count + 1) if area[k] * p.cell**2 >= p.min_area
                    and raised_in[k] >= p.min_standing_share * every_in[k])
    return StandingGrid(up, points[standing, 2], labels, flat[where[standing]], counted, low, p.cell, T_cloud_table,
                        p.sigmas, p.min_height)
