"""segment(): a table-top cloud into the objects standing on the table, by colour and distance.

The table is the largest plane (psorr.geometry.support_plane); what stands above it, inside its
outline, is voxelised, each voxel labelled with one of a few colour models by a graph cut
(psorr.segment.colour_cut), and neighbouring voxels of one colour label joined into clusters
(psorr.segment.clusters). A cloud without colours is clustered by distance alone. Each cluster is
then split where its surface folds inwards, as two objects touching do (psorr.segment.convexity).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, fields

import numpy as np
import open3d as o3d
from scipy.spatial import Delaunay, cKDTree

from psorr.checks import params as check
from psorr.checks.arrays import random_generator
from psorr.checks.clouds import require_sensor_metres
from psorr.decomposition.preprocess import neighbourhood_normals, voxel_downsample
from psorr.decomposition.support_crop import along_plane
from psorr.errors import InvalidInputError
from psorr.geometry.support_plane import support_plane
from psorr.segment.clusters import absorb_small, conditional_clusters, merge_unless_distinct
from psorr.segment.colour import colour_name, rgb_to_lab
from psorr.segment.colour_cut import colour_cut, colour_models, weighted_lab
from psorr.segment.convexity import (
    concave_edges,
    crease_voxels,
    grow_into,
    join_unless_concave,
    median_bend,
)
from psorr.sensing.noise_context import depth_noise
from psorr.types import PointCloud


@dataclass(frozen=True)
class SegmentParams:
    """Settings of segmentation; distances in metres, colour distances in CIELAB units (about 2.3 is
    the least difference a person sees)."""

    voxel_size: float = 0.005        # the working grid: a few Kinect pixels at a metre
    neighbours: int = 10             # k of the voxels' neighbour graph
    tolerance_voxels: float = 2.0    # neighbours closer than this many voxels may join one cluster
    height_sigmas: float = 3.0       # a point stands on the table above this many depth sigmas...
    min_height: float = 0.004        # ...and at least this high
    max_colours: int = 8             # colour models drawn by k-means before merging
    merge_colour: float = 18.0       # models closer than this are one colour
    colour_sigma: float = 9.0        # a surface's colour noise (Kinect RGB under room light)
    lightness_weight: float = 0.5    # shading moves lightness more than hue
    smoothness: float = 1.0          # Potts weight of two neighbours of one colour
    min_voxels: int = 20             # a smaller cluster joins the neighbour it touches most
    even_spread: float = 10.0        # a cluster whose colours spread less is evenly coloured
    crease_noise: float | None = 2.0  # a fold over this many times the normals' noise is a crease; None: no split

    def __post_init__(self):
        check.positive(self, "voxel_size", "tolerance_voxels", "height_sigmas", "merge_colour", "colour_sigma",
                       "lightness_weight", "even_spread")
        check.non_negative(self, "min_height", "smoothness")
        check.whole(self, "neighbours", "max_colours", "min_voxels")
        check.positive(self, "crease_noise", optional=True)

    @classmethod
    def names(cls) -> list[str]:
        return [f.name for f in fields(cls)]


@dataclass(frozen=True, eq=False)
class Segment:
    """One segment: id (its label), n_points, centroid (3,) metres, mean_rgb (3,) in [0, 1] (None for a
    cloud without colours), and the palette's name for it."""

    id: int
    n_points: int
    centroid: np.ndarray
    mean_rgb: np.ndarray | None
    colour: str | None


@dataclass(frozen=True)
class SegmentStats:
    total_ms: float
    n_colour_models: int  # 0 for a cloud without colours
    n_voxels: int


@dataclass(frozen=True, eq=False)
class Segmentation:
    """labels (N,) int64: each point's segment, or -1 (the table, what is off it, NaN points);
    segments: largest first; table_plane: (4,) or None when the cloud has no table."""

    labels: np.ndarray
    segments: tuple[Segment, ...]
    table_plane: np.ndarray | None
    stats: SegmentStats


def standing_rows(cloud: PointCloud, params: SegmentParams) -> tuple[np.ndarray, np.ndarray | None]:
    """(rows of the points standing on the table inside its outline, the table plane or None). Without
    a table, every finite point in front of the sensor."""
    rows = np.flatnonzero(cloud.valid_mask)
    rows = rows[cloud.points[rows, 2] > 1e-6]
    down = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud.points[rows])).voxel_down_sample(0.01)
    table = support_plane(down)
    if table is None:
        return rows, None
    along, height = along_plane(cloud.points[rows], table.plane)
    z = cloud.points[rows, 2]
    above = height > np.maximum(params.min_height, params.height_sigmas * depth_noise().depth_sigma(z))
    outline, _ = along_plane(np.asarray(down.points)[table.inliers], table.plane)
    inside = Delaunay(outline[_hull(outline)]).find_simplex(along[above]) >= 0
    return rows[np.flatnonzero(above)[inside]], table.plane


def _hull(points: np.ndarray) -> np.ndarray:
    from scipy.spatial import ConvexHull

    return ConvexHull(points).vertices


def segment(cloud: PointCloud, params: SegmentParams | None = None,
            rng: np.random.Generator | None = None) -> Segmentation:
    """Segment the objects standing on the table of ``cloud`` (metres, sensor frame, optionally coloured)."""
    if not isinstance(cloud, PointCloud):
        raise InvalidInputError(f"segment() takes a psorr.PointCloud, got {type(cloud).__name__}")
    require_sensor_metres(cloud, "segment(): the cloud")
    params = params or SegmentParams()
    check.require_instance(params, SegmentParams, "segment()'s params", "pass SegmentParams(...), or None")
    rng = random_generator(rng, "segment()")
    start = time.perf_counter()
    rows, plane = standing_rows(cloud, params)
    labels = np.full(len(cloud), -1, dtype=np.int64)
    if len(rows) == 0:
        return Segmentation(labels, (), plane, SegmentStats((time.perf_counter() - start) * 1e3, 0, 0))
    centroids, voxel_of = voxel_downsample(cloud.points[rows], params.voxel_size)
    edge_i, edge_j, near, neighbours = _edges(centroids, params)
    n_models, same = 0, np.ones(len(edge_i), dtype=bool)
    if cloud.colors is not None and np.isfinite(cloud.colors[rows]).all():
        counts = np.bincount(voxel_of, minlength=len(centroids))[:, None]
        rgb = np.column_stack([np.bincount(voxel_of, cloud.colors[rows, k], len(centroids)) for k in range(3)])
        colours = weighted_lab(rgb_to_lab(rgb / counts), params.lightness_weight)
        models = colour_models(colours, params.max_colours, params.merge_colour, rng)
        colour_of, models = colour_cut(colours, (edge_i, edge_j), models, params.colour_sigma, params.smoothness,
                                       rng)
        n_models, same = len(models), colour_of[edge_i] == colour_of[edge_j]
    clusters = conditional_clusters(len(centroids), edge_i, edge_j, near & same)
    clusters = absorb_small(clusters, edge_i, edge_j, near, params.min_voxels)
    if n_models:
        clusters = merge_unless_distinct(clusters, colours, edge_i, edge_j, near, params.even_spread,
                                         params.merge_colour)
    if params.crease_noise is not None:
        clusters = _split_at_creases(centroids, neighbours, clusters, edge_i, edge_j, near, params)
    labels[rows] = clusters[voxel_of]
    segments = _segments(cloud, labels)
    return Segmentation(labels, segments, plane,
                        SegmentStats((time.perf_counter() - start) * 1e3, n_models, len(centroids)))


def _split_at_creases(centroids, neighbours, clusters, edge_i, edge_j, near, params: SegmentParams) -> np.ndarray:
    """Each cluster split where its surface folds inwards by over ``crease_noise`` times the median bend
    between neighbours' normals (their noise: most neighbours lie on one smooth surface). Crease voxels
    are set aside, the rest joined by their edges within the cluster, the crease voxels grown back into
    the parts they touch, and two parts joined again unless most of the edges between them are concave."""
    edge_i, edge_j = edge_i[near], edge_j[near]
    # PCA normals over each voxel and its nearest (``neighbours`` points in all), facing the sensor.
    normals, _ = neighbourhood_normals(centroids, neighbours[:, :params.neighbours - 1])
    bend = params.crease_noise * median_bend(normals, edge_i, edge_j) if len(edge_i) else 0.0
    concave = concave_edges(centroids, normals, edge_i, edge_j, bend)
    crease = crease_voxels(len(centroids), edge_i, edge_j, concave)
    inside = (clusters[edge_i] == clusters[edge_j]) & (clusters[edge_i] >= 0)
    seeds = inside & ~crease[edge_i] & ~crease[edge_j]
    parts = np.where(crease, -1, conditional_clusters(len(centroids), edge_i, edge_j, seeds))
    parts = grow_into(parts, edge_i[inside], edge_j[inside], crease)
    alone = parts < 0
    parts[alone] = parts.max(initial=-1) + 1 + np.arange(int(alone.sum()))
    parts = absorb_small(parts, edge_i, edge_j, inside, params.min_voxels)
    return join_unless_concave(parts, edge_i[inside], edge_j[inside], concave[inside])


def _edges(centroids: np.ndarray, params: SegmentParams):
    """Undirected neighbour pairs (i, j) of the voxels, each once, which lie within the tolerance, and
    each voxel's nearest others (N, k)."""
    k = min(params.neighbours, len(centroids) - 1)
    if k < 1:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, np.zeros(0, dtype=bool), np.zeros((len(centroids), 0), dtype=np.int64)
    _, idx = cKDTree(centroids).query(centroids, k=k + 1)
    i, j = np.repeat(np.arange(len(centroids)), k), idx[:, 1:].ravel()
    keys = np.unique(np.minimum(i, j) * len(centroids) + np.maximum(i, j))  # one flat key a pair: sorts fast
    first, second = keys // len(centroids), keys % len(centroids)
    length = np.linalg.norm(centroids[first] - centroids[second], axis=1)
    return first, second, length < params.tolerance_voxels * params.voxel_size, idx[:, 1:]


def _segments(cloud: PointCloud, labels: np.ndarray) -> tuple[Segment, ...]:
    out = []
    for sid in range(int(labels.max()) + 1):
        members = labels == sid
        rgb = None if cloud.colors is None else cloud.colors[members].mean(axis=0)
        out.append(Segment(sid, int(members.sum()), cloud.points[members].mean(axis=0), rgb,
                           None if rgb is None else colour_name(rgb)))
    return tuple(out)
