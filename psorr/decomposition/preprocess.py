"""Preprocessing: voxel downsampling with a map back, a k-NN graph, and
normals oriented towards the sensor."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from psorr.errors import TooSparseError
from psorr.geometry.columns import column_max, column_min
from psorr.sensing.resolution import pixel_samples
from psorr.types import PointCloud


@dataclass(frozen=True, eq=False)
class Voxelized:
    """The decomposition's working set.

    Attributes:
        points: (M, 3) voxel centroids, metres.
        normals: (M, 3) unit normals, each pointing towards the sensor origin.
        curvature: (M,) surface variation lambda_min / sum(lambda) of each
            neighbourhood, 0 on a perfect plane.
        voxel_of: (N,) for every point of the input cloud, the voxel it fell
            into, or -1 for NaN points.
        neighbours: (M, k) indices of each voxel's k nearest voxels (itself excluded).
        neighbour_dist: (M, k) their distances, metres.
        n_sampled: the finite points the voxels were built from.
    """

    points: np.ndarray
    normals: np.ndarray
    curvature: np.ndarray
    voxel_of: np.ndarray
    neighbours: np.ndarray
    neighbour_dist: np.ndarray
    n_sampled: int

    def __len__(self) -> int:
        return len(self.points)


_DENSE_GRID_CELLS = 8_000_000  # a table-top scene at 1 cm needs well under 1M


def voxel_downsample(points: np.ndarray, voxel_size: float, normals: np.ndarray | None = None):
    """Average (N, 3) finite points per voxel. Returns (centroids (M, 3), voxel_of (N,)).

    With (N, 3) normals, points whose normals point different ways (the two
    sides of a thin sheet) go to different voxels even when they are closer
    than a voxel, so their normals never average away.
    """
    keys = np.floor(points / voxel_size).astype(np.int64)
    keys -= column_min(keys)
    dims = column_max(keys) + 1
    if normals is not None:
        dominant = np.abs(normals).argmax(axis=1)
        keys = np.column_stack([keys, dominant * 2 + (normals[np.arange(len(normals)), dominant] > 0)])
        dims = np.r_[dims, 6]
    n_cells = math.prod(int(d) for d in dims)  # Python ints: a stray far point or a tiny voxel overflows int64
    if n_cells >= 2**62:
        # No flat key fits in int64: the occupied cells are numbered by sorting their rows instead.
        voxel_of = np.unique(keys, axis=0, return_inverse=True)[1].ravel()
        m = int(voxel_of.max()) + 1
    elif n_cells <= _DENSE_GRID_CELLS:
        flat = _flat_keys(keys, dims)
        # Counting over a dense grid is linear; sorting the keys costs several times more.
        occupied = np.bincount(flat, minlength=n_cells) > 0
        cell_to_voxel = np.cumsum(occupied) - 1
        voxel_of = cell_to_voxel[flat]
        m = int(cell_to_voxel[-1]) + 1
    else:
        flat = _flat_keys(keys, dims)
        order = np.argsort(flat)
        sorted_keys = flat[order]
        starts = np.r_[True, sorted_keys[1:] != sorted_keys[:-1]]
        voxel_sorted = np.cumsum(starts) - 1
        voxel_of = np.empty_like(voxel_sorted)
        voxel_of[order] = voxel_sorted
        m = int(voxel_sorted[-1]) + 1
    counts = np.bincount(voxel_of, minlength=m)
    centroids = np.column_stack([np.bincount(voxel_of, points[:, k], m) for k in range(3)])
    return centroids / counts[:, None], voxel_of


def _flat_keys(keys: np.ndarray, dims: np.ndarray) -> np.ndarray:
    """One int64 per row of cell coordinates (N, D) on a grid of ``dims`` (D,) cells (< 2**62 in all)."""
    flat = keys[:, 0]
    for k in range(1, len(dims)):
        flat = flat * dims[k] + keys[:, k]
    return flat


def smallest_eigenpairs(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Smallest eigenvalue (N,) and unit eigenvector (N, 3) of (N, 3, 3)
    symmetric PSD matrices, in closed form: batched LAPACK spends most of its
    time on per-matrix overhead at this size."""
    a, b, c = cov[:, 0, 0], cov[:, 1, 1], cov[:, 2, 2]
    d, e, f = cov[:, 0, 1], cov[:, 1, 2], cov[:, 0, 2]
    # Trigonometric solution of the characteristic cubic (Smith 1961).
    q = (a + b + c) / 3.0
    p1 = d * d + e * e + f * f
    p2 = (a - q) ** 2 + (b - q) ** 2 + (c - q) ** 2 + 2.0 * p1
    p = np.sqrt(np.maximum(p2 / 6.0, 1e-300))
    ba, bb, bc = (a - q) / p, (b - q) / p, (c - q) / p
    bd, be, bf = d / p, e / p, f / p
    det = ba * (bb * bc - be * be) - bd * (bd * bc - be * bf) + bf * (bd * be - bb * bf)
    phi = np.arccos(np.clip(det / 2.0, -1.0, 1.0)) / 3.0
    lam = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    # The eigenvector is orthogonal to the rows of (cov - lam I): take the
    # longest cross product of two rows, which is the best conditioned.
    r0 = np.column_stack([a - lam, d, f])
    r1 = np.column_stack([d, b - lam, e])
    r2 = np.column_stack([f, e, c - lam])
    crosses = np.stack([np.cross(r0, r1), np.cross(r0, r2), np.cross(r1, r2)])
    lengths = np.linalg.norm(crosses, axis=2)
    best = np.argmax(lengths, axis=0)
    rows = np.arange(len(cov))
    vec = crosses[best, rows] / np.maximum(lengths[best, rows], 1e-300)[:, None]
    degenerate = lengths[best, rows] < 1e-24
    vec[degenerate] = (0.0, 0.0, 1.0)  # an isotropic blob: no preferred normal
    return np.maximum(lam, 0.0), vec


def neighbourhood_normals(points: np.ndarray, neighbours: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """PCA normals and surface variation (lambda_min / trace) from each point's
    neighbourhood, the normal flipped to face the sensor at the origin."""
    hood = points[np.concatenate([np.arange(len(points))[:, None], neighbours], axis=1)]
    centred = hood - hood.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", centred, centred)
    lam, normals = smallest_eigenpairs(cov)
    flip = np.einsum("ij,ij->i", normals, points) > 0
    normals[flip] *= -1
    curvature = lam / np.maximum(np.trace(cov, axis1=1, axis2=2), 1e-18)
    return normals, curvature


def preprocess(cloud: PointCloud, voxel_size: float, k_neighbours: int,
               sensor_focal: float | None = None) -> Voxelized:
    """Downsample the finite points of `cloud` and build the k-NN graph.

    A cloud that carries normals (say, sampled from a CAD mesh) keeps them,
    averaged per voxel; otherwise they are estimated and made to face the sensor.
    A cloud sampled finer than a sensor of `sensor_focal` pixels (None: never
    thinned) builds its voxels from one row per pixel of that sensor's image
    (psorr.sensing.resolution), and every other finite point belongs to the voxel
    of its pixel's row.
    """
    valid = cloud.valid_mask
    n_valid = int(valid.sum())
    if n_valid < k_neighbours + 1:
        raise TooSparseError(
            f"the cloud has {n_valid} finite points; decomposition needs at least {k_neighbours + 1}"
        )
    given = None if cloud.normals is None else cloud.normals[valid]
    points = cloud.points if n_valid == len(cloud) else cloud.points[valid]
    sampled = None if sensor_focal is None else pixel_samples(cloud, sensor_focal)
    if sampled is None or not sampled.finer:
        centroids, voxel_of_valid = voxel_downsample(points, voxel_size, given)
    else:
        # Every point joins the voxel of the row its pixel kept; the final distance test sorts out the
        # points behind that surface.
        centroids, voxel_of_sampled = voxel_downsample(cloud.points[sampled.kept], voxel_size)
        of_valid = sampled.sample_of[valid]
        voxel_of_valid = np.where(of_valid >= 0, voxel_of_sampled[of_valid], -1)
    if len(centroids) < k_neighbours + 1:
        raise TooSparseError(
            f"its points fill only {len(centroids)} voxels of {voxel_size} m, and decomposition needs at least "
            f"{k_neighbours + 1}; use a smaller voxel_size"
        )
    voxel_of = np.full(len(cloud), -1, dtype=np.int64)
    voxel_of[valid] = voxel_of_valid
    dist, idx = cKDTree(centroids).query(centroids, k=k_neighbours + 1)
    neighbours, neighbour_dist = idx[:, 1:], dist[:, 1:]
    normals, curvature = neighbourhood_normals(centroids, neighbours)
    if given is not None:
        held = voxel_of_valid >= 0
        summed = np.column_stack([np.bincount(voxel_of_valid[held], given[held, k], len(centroids))
                                  for k in range(3)])
        length = np.linalg.norm(summed, axis=1, keepdims=True)
        normals = np.where(length > 1e-9, summed / np.maximum(length, 1e-12), normals)
    n_sampled = n_valid if sampled is None or not sampled.finer else len(sampled.kept)
    return Voxelized(centroids, normals, curvature, voxel_of, neighbours, neighbour_dist, n_sampled)


def undirected_edges(vox: Voxelized) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The k-NN graph as undirected edges, each once: (i, j, length)."""
    m, k = vox.neighbours.shape
    i = np.repeat(np.arange(m), k)
    j = vox.neighbours.ravel()
    # i -> j duplicates j -> i only when i is also among j's neighbours; keep that pair once.
    mutual = (vox.neighbours[j] == i[:, None]).any(axis=1)
    keep = ~mutual | (i < j)
    return i[keep], j[keep], vox.neighbour_dist.ravel()[keep]
