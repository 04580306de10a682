"""What stands on the supporting plane, plus a margin of the plane around it.

A table top fills most of a Kinect frame, and the decomposition's graph cut and
preprocessing cost grows with every voxel of it, though only the parts matter.
The plane's far reaches are blanked out before decomposing. A band of it is kept
around everything that stands on it, measured along the plane, so a part's
lowest faces are cut out of the table as they would be in the whole cloud, a
thin part's flat regions (a board under its components, a bracket's base) stay,
and the kept table is still larger than any model.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.ndimage import binary_dilation
from scipy.spatial import cKDTree

from psorr.checks import params as check
from psorr.geometry.boxes import orthonormal_frame
from psorr.sensing.noise_context import depth_noise
from psorr.types import PointCloud, PrimitiveKind

_MAX_GRID_CELLS = 20_000_000  # 20 MB of bools: a 1 cm grid 44 m square


@dataclass(frozen=True)
class SupportCropParams:
    """Distances in metres."""

    enabled: bool = True
    off_plane: float = 0.008  # a point farther than this above the supporting plane stands on it
    cell: float = 0.01        # grid on the plane that the band is measured on
    # The bar rises where the sensor's noise would lift a point of the plane itself past it (False: CAD samples).
    sensor_noise: bool = True

    def __post_init__(self):
        check.flag(self, "enabled", "sensor_noise")
        check.positive(self, "off_plane", "cell", unit=" metres")


def standing_bar(points: np.ndarray, plane: np.ndarray, params: SupportCropParams,
                 n_points: int | None = None) -> np.ndarray:
    """(N,) the height (m) over the supporting ``plane`` (a, b, c, d; unit normal) past which each of ``points``
    (N, 3), of a cloud of ``n_points`` finite points (None: these), stands on it: ``off_plane``, or where the
    sensor's noise is larger the height its noise lifts fewer than one of the cloud's points of the plane itself
    past (a Kinect seeing a table 2 m away lifted 581 of its 269,000 points past 8 mm;
    docs/decisions/0010-support-crop.md)."""
    n_points = len(points) if n_points is None else n_points
    bar = np.full(len(points), params.off_plane)
    if params.sensor_noise and n_points > 1:
        bar = np.maximum(bar, depth_noise().height_lifted(points, plane[:3], 1.0 / n_points))
    return bar


def past_bar(points: np.ndarray, heights: np.ndarray, plane: np.ndarray, params: SupportCropParams) -> np.ndarray:
    """(N,) bool: does each of a cloud's finite ``points`` (N, 3) lie farther from the ``plane`` than
    :func:`standing_bar` (``heights`` (N,) its signed heights over it)? The bar is never below ``off_plane``, so
    the noise is looked up only for the few points past that: most of a frame is table."""
    past = np.abs(heights) > params.off_plane
    past[past] = np.abs(heights[past]) > standing_bar(points[past], plane, params, len(points))
    return past


def standing_points(cloud: PointCloud, plane: np.ndarray | None, params: SupportCropParams) -> np.ndarray:
    """(N,) bool over ``cloud``'s points: finite, and standing on the supporting ``plane`` (a, b, c, d; the sensor
    on its positive side) by :func:`standing_bar`; every finite point when there is no plane."""
    finite = cloud.valid_mask
    standing = finite.copy()
    if plane is not None:
        points = cloud.points[finite]
        heights = points @ np.asarray(plane[:3]) + plane[3]
        standing[finite] = (heights > 0) & past_bar(points, heights, plane, params)
    return standing


def along_plane(points: np.ndarray, plane: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates (N, 2) of ``points`` (N, 3) along the ``plane`` (a, b, c, d; unit normal), on two axes
    orthogonal to its normal, and their heights (N,) above it; metres."""
    normal = np.asarray(plane[:3], dtype=float)
    return points @ np.column_stack(orthonormal_frame(normal)), points @ normal + plane[3]


def crop_to_parts(cloud: PointCloud, plane: np.ndarray | None, margin: float,
                  params: SupportCropParams = SupportCropParams()) -> PointCloud:
    """``cloud`` with the points of the supporting ``plane`` (a, b, c, d; unit normal, the sensor on
    its positive side) that lie more than ``margin`` metres, along the plane, from anything standing
    on it, and every point below it, made NaN. Point order stays, so labels computed on the result
    index ``cloud``. Without a plane, or with nothing standing on it, the cloud comes back unchanged."""
    if not params.enabled or plane is None:
        return cloud
    finite, cells, off, below = _on_grid(cloud, plane, params)
    if not off.any():
        return cloud
    reach = int(np.ceil(margin / params.cell)) + 1  # one cell more: a point may sit anywhere in its cell
    # Below the plane (a floor seen past the table's edge) no part can be: it goes too.
    far = below | (~off & ~_near_cells(cells, off, reach))
    if not far.any():
        return cloud
    cropped = cloud.points.copy()
    cropped[finite[far]] = np.nan
    return replace(cloud, points=cropped)


def band_rim(cloud: PointCloud, plane: np.ndarray, margin: float,
             params: SupportCropParams = SupportCropParams()) -> np.ndarray:
    """(N,) bool over the points of ``cloud`` (cropped by :func:`crop_to_parts` with ``margin``): those of the
    band's outer two cells, the points farthest along the ``plane`` from anything standing on it."""
    finite, cells, off, _ = _on_grid(cloud, plane, params)
    rim = np.zeros(len(cloud.points), dtype=bool)
    if not off.any():
        return rim
    inner = int(np.ceil(margin / params.cell)) - 1  # crop_to_parts keeps up to this plus two
    rim[finite[~off & ~_near_cells(cells, off, max(inner, 1))]] = True
    return rim


def table_in_band(primitives, labels: np.ndarray, rim: np.ndarray) -> int:
    """The index of the plane among ``primitives`` (labels (N,) naming each point's) that holds the most points
    of the band's ``rim`` (:func:`band_rim`): the table, which reaches past the band on every side. -1 when no
    plane holds any."""
    held = np.bincount(labels[rim & (labels >= 0)], minlength=len(primitives))
    planes = [k for k, p in enumerate(primitives) if p.kind is PrimitiveKind.PLANE and held[k] > 0]
    return max(planes, key=lambda k: held[k]) if planes else -1


def _on_grid(cloud: PointCloud, plane: np.ndarray, params: SupportCropParams):
    """The indices (M,) of the finite points of ``cloud``, their cells (M, 2) of the grid along the ``plane``,
    and which of them (M,) stand on it and which lie below it, by :func:`standing_bar`."""
    finite = np.flatnonzero(cloud.valid_mask)
    along, height = along_plane(cloud.points[finite], plane)
    past = past_bar(cloud.points[finite], height, plane, params)
    # Column by column: a reduction over axis 0 of an (N, 2) array took 5-7 ms on a 640x480 cloud.
    lowest = np.array([along[:, 0].min(), along[:, 1].min()]) if len(along) else np.zeros(2)
    cells = np.floor((along - lowest) / params.cell).astype(np.int64)
    return finite, cells, past & (height > 0), past & (height < 0)


def _near_cells(cells: np.ndarray, occupied: np.ndarray, reach: int) -> np.ndarray:
    """(N,) bool: is each grid cell (N, 2) within ``reach`` cells (Euclidean) of a cell of the ``occupied`` (N,)
    points? Dilated on a grid over the occupied cells' window, which is small for a table top; a stray point
    metres away would make that grid gigabytes, and is looked up in a k-d tree of the occupied cells instead."""
    hx, hy = cells[occupied, 0], cells[occupied, 1]  # columns: reductions over axis 0 are slow (see above)
    x0, y0 = int(hx.min()) - reach, int(hy.min()) - reach
    nx, ny = int(hx.max()) + reach + 1 - x0, int(hy.max()) + reach + 1 - y0
    if nx * ny > _MAX_GRID_CELLS:
        tree = cKDTree(np.unique(np.column_stack([hx, hy]), axis=0))
        return np.isfinite(tree.query(cells, distance_upper_bound=reach + 1e-6)[0])
    grid = np.zeros((nx, ny), dtype=bool)
    grid[hx - x0, hy - y0] = True
    ring = np.hypot(*np.mgrid[-reach:reach + 1, -reach:reach + 1]) <= reach
    grid = binary_dilation(grid, structure=ring)
    x, y = cells[:, 0] - x0, cells[:, 1] - y0
    inside = np.flatnonzero((x >= 0) & (x < nx) & (y >= 0) & (y < ny))
    near = np.zeros(len(cells), dtype=bool)
    near[inside] = grid[x[inside], y[inside]]
    return near
