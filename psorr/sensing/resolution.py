"""Clouds sampled finer than the sensor the thresholds suit, thinned to its sampling.

The decomposition's and the checks' thresholds are set in the sensor's noise and in points: a 3M-point
cloud of a structured-light sensor holds ten times a Kinect's points on every face, and noise tails then
fill voxels a Kinect leaves empty, so the same scene decomposed into more primitives and its parts went
unfound (docs/decisions/0050). A cloud sampled finer than ``focal`` pixels' worth of viewing directions
is therefore thinned to one point per direction cell of 1 / ``focal`` radians, as a sensor of that
focal length would have sampled the same scene. A cloud already that coarse passes unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.sensing.noise_context import depth_noise
from psorr.types import PointCloud

# Points per occupied pixel at which a cloud counts as finer than the sensor (docs/decisions/0050): the
# checks take a finer grid's own pixel pitch, and a 1280x720 image at 910 px (3 a pixel) did better so
# than thinned; a 1280x960 one at 1050 px (4 a pixel) did worse.
FINER_BY = 3.5


@dataclass(frozen=True, eq=False)
class ThinnedCloud:
    """A cloud thinned to a sensor's sampling.

    Attributes:
        cloud: the thinned cloud, organised as the depth image of a pinhole camera of the given focal
            length at the origin (NaN where no point fell); the input itself when not thinned.
        kept: (M,) indices of the input rows it holds, in its row order (all rows when not thinned).
        points_per_cell: the input's finite points per occupied pixel, as counted (thinned when at least
            FINER_BY); 1.0 when not counted: an organised cloud whose own grid is too coarse to thin is
            judged by the grid alone, and a cloud with no point in front of the sensor.
    """

    cloud: PointCloud
    kept: np.ndarray
    points_per_cell: float

    @property
    def thinned(self) -> bool:
        return self.points_per_cell >= FINER_BY


_NOISE_SPAN = 6.0  # depth sigmas: the spread of one surface's samples along a ray (+-3 sigma)
_DENSE_CELLS = 1 << 24  # direction grids up to this many cells are counted densely (a Kinect's is 0.3M)


@dataclass(frozen=True, eq=False)
class _Cells:
    """Points (N, 3) binned into pixels of a pinhole image 1 / focal radians a pixel: pixel (N,) is each
    point's row-major pixel in a width x height image, or its rank among the occupied pixels when the
    image would be too large to hold (width and height then None)."""

    pixel: np.ndarray
    n_pixels: int
    width: int | None
    height: int | None
    corner: tuple[int, int]  # (u, v) of pixel 0 in whole pixels from the optical axis


def _cells(points: np.ndarray, focal: float) -> _Cells:
    u = np.floor(points[:, 0] / points[:, 2] * focal).astype(np.int64)
    v = np.floor(points[:, 1] / points[:, 2] * focal).astype(np.int64)
    corner = (int(u.min()), int(v.min()))
    u -= corner[0]
    v -= corner[1]
    width, height = int(u.max()) + 1, int(v.max()) + 1
    if width * height <= _DENSE_CELLS:
        return _Cells(v * width + u, width * height, width, height, corner)
    # A cloud reaching out sideways: number the occupied pixels by sorting, and give up the image.
    pixel = np.unique(v * width + u, return_inverse=True)[1].ravel()
    return _Cells(pixel, int(pixel.max()) + 1, None, None, corner)


def _on_pixel_rays(points: np.ndarray, cells: _Cells, pixels: np.ndarray, focal: float) -> np.ndarray:
    """points (M, 3) moved along their depth onto the central rays of their pixels (M,), as a depth
    camera reports them: each by at most half a pixel, a millimetre at a metre for a Kinect. Off the
    ray, they would fall into the checks' depth buffer two to a pixel beside empty ones, and a true
    part would look seen through its holes."""
    u = pixels % cells.width + cells.corner[0] + 0.5
    v = pixels // cells.width + cells.corner[1] + 0.5
    z = points[:, 2]
    return np.column_stack([u / focal * z, v / focal * z, z])


def _first_on_nearest_surface(points: np.ndarray, cells: _Cells, focal: float) -> np.ndarray:
    """(n_pixels,) the index of each pixel's first point, in row order, on the nearest surface it sees,
    or len(points) for an empty pixel.

    A sensor sees only the nearest surface along a ray: a cloud merged from several views, or sampled
    from a scene's surfaces, may hold a table's points under a box's in one pixel. The nearest surface is
    what lies within the sensor's noise span of the pixel's nearest point; its first point, not its
    nearest, since the nearest of many noisy samples sits biased towards the sensor."""
    z = points[:, 2]
    nearest = np.full(cells.n_pixels, np.inf)
    np.minimum.at(nearest, cells.pixel, z)
    reach = nearest + _NOISE_SPAN * depth_noise().depth_sigma(np.where(np.isfinite(nearest), nearest, 1.0), focal)
    front = np.flatnonzero(z <= reach[cells.pixel])
    first = np.full(cells.n_pixels, len(points))
    np.minimum.at(first, cells.pixel[front], front)
    return first


@dataclass(frozen=True, eq=False)
class PixelSamples:
    """A cloud's rows sampled one to a pixel of a pinhole image at its origin (see thin_to_focal).

    Attributes:
        kept: (M,) the rows kept, one per occupied pixel, in pixel order.
        sample_of: (N,) for every row of the cloud, the index into ``kept`` of its pixel's kept row, or
            -1 (a NaN row, or one behind the sensor).
        points_per_cell: the cloud's finite points per occupied pixel.
        cells: the pixels, for building the image.
        occupied: (M,) the pixel of each kept row.
    """

    kept: np.ndarray
    sample_of: np.ndarray
    points_per_cell: float
    cells: _Cells
    occupied: np.ndarray

    @property
    def finer(self) -> bool:
        return self.points_per_cell >= FINER_BY


def pixel_samples(cloud: PointCloud, focal: float) -> PixelSamples | None:
    """One row per pixel of a ``focal``-pixel pinhole image at the origin (see _first_on_nearest_surface);
    None when no finite point lies in front of the sensor, or when the cloud is an image whose own grid
    is too coarse to be thinned (a Kinect's, say: told from its columns in a few milliseconds)."""
    if cloud.is_organised:
        own = grid_focal(cloud)
        if own is not None and (own / focal) ** 2 < FINER_BY:
            return None
    rows = np.flatnonzero(cloud.valid_mask)
    rows = rows[cloud.points[rows, 2] > 1e-6]
    if len(rows) == 0:
        return None
    cells = _cells(cloud.points[rows], focal)
    first = _first_on_nearest_surface(cloud.points[rows], cells, focal)
    occupied = np.flatnonzero(first < len(rows))
    index_of_pixel = np.full(cells.n_pixels, -1, dtype=np.int64)
    index_of_pixel[occupied] = np.arange(len(occupied))
    sample_of = np.full(len(cloud.points), -1, dtype=np.int64)
    sample_of[rows] = index_of_pixel[cells.pixel]
    return PixelSamples(rows[first[occupied]], sample_of, len(rows) / len(occupied), cells, occupied)


def grid_focal(cloud: PointCloud) -> float | None:
    """The horizontal focal length (pixels) of an organised cloud's pinhole grid, fitted from its columns
    u = f x / z + c; None when too few points fit it to within a pixel (not a pinhole image)."""
    rows = np.flatnonzero(cloud.valid_mask)[::7]  # every 7th of 300 000 fits as well, 7x faster
    rows = rows[cloud.points[rows, 2] > 1e-3]
    if len(rows) < 100:
        return None
    slope = cloud.points[rows, 0] / cloud.points[rows, 2]
    u = (rows % cloud.width).astype(np.float64)
    (focal, centre), *_ = np.linalg.lstsq(np.column_stack([slope, np.ones_like(slope)]), u, rcond=None)
    rms = float(np.sqrt(np.mean((focal * slope + centre - u) ** 2)))
    return float(focal) if focal > 0 and rms < 1.0 else None


def thin_to_focal(cloud: PointCloud, focal: float) -> ThinnedCloud:
    """``cloud`` (metres, seen from the origin) thinned to the image a pinhole camera of ``focal`` pixels at
    the origin would take of it, when it holds at least FINER_BY finite points a pixel of that image;
    otherwise the cloud itself. Each pixel keeps one input point (see _first_on_nearest_surface) at its
    depth on the pixel's central ray, and the image is organised (NaN where empty), so the checks read
    it as they read a camera's."""
    samples = pixel_samples(cloud, focal)
    if samples is None or not samples.finer:
        per_cell = 1.0 if samples is None else samples.points_per_cell
        return ThinnedCloud(cloud, np.arange(len(cloud.points)), per_cell)
    kept, cells = samples.kept, samples.cells
    if cells.width is None:  # no image to hold them: the kept points alone, in row order
        order = np.argsort(kept)
        kept, slots, size, shape = kept[order], np.arange(len(kept)), len(kept), {}
        points = cloud.points[kept]
    else:
        slots, size, shape = samples.occupied, cells.n_pixels, {"width": cells.width, "height": cells.height}
        points = _on_pixel_rays(cloud.points[kept], cells, samples.occupied, focal)
    thinned = PointCloud(_scatter(points, slots, size, np.nan),
                         normals=None if cloud.normals is None else _scatter(cloud.normals[kept], slots, size, np.nan),
                         colors=None if cloud.colors is None else _scatter(cloud.colors[kept], slots, size, np.nan),
                         labels=None if cloud.labels is None else _scatter(cloud.labels[kept], slots, size, -1),
                         **shape)
    return ThinnedCloud(thinned, kept, samples.points_per_cell)


def _scatter(values: np.ndarray, slots: np.ndarray, size: int, empty) -> np.ndarray:
    out = np.full((size, *values.shape[1:]), empty, dtype=values.dtype)
    out[slots] = values
    return out
