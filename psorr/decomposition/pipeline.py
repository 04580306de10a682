"""decompose(): a cloud into planes and cylinders and their shape graph (section 2.1.1)."""

from __future__ import annotations

import time
from dataclasses import dataclass, fields

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from psorr.checks import params as check
from psorr.checks.arrays import random_generator
from psorr.checks.clouds import require_sensor_metres
from psorr.decomposition.graphcut import alpha_expansion
from psorr.decomposition.hypotheses import generate_hypotheses, support_mask
from psorr.decomposition.merge import Piece, merge_greedy
from psorr.decomposition.preprocess import Voxelized, preprocess, undirected_edges
from psorr.decomposition.psg import graph_edges
from psorr.errors import InvalidInputError
from psorr.geometry import shapes
from psorr.geometry.boxes import box_around_axis
from psorr.geometry.columns import column_mean
from psorr.sensing.noise_context import depth_noise
from psorr.types import PointCloud, Primitive, PrimitiveKind, PrimitiveShapeGraph


@dataclass(frozen=True)
class DecomposeParams:
    """Settings of the decomposition; the defaults suit a Kinect v1 cloud of a table top.

    Distances are metres. Thresholds that scale with sensor noise are given in multiples of
    the sensor model's depth sigma at each point's depth (``RecognizeParams.sensor``; a Kinect v1's).
    """

    voxel_size: float = 0.012
    k_neighbours: int = 8
    sensor_noise: bool = True          # False: one threshold for all depths (CAD samples), and no thinning
    sensor_focal: float = 525.0        # px: a sensor cloud sampled finer is thinned to this (Kinect v1) sampling
    thin_finer: bool = True            # False: never thinned (a cloud thinned already)
    inlier_sigmas: float = 2.5         # inlier distance = max(min_inlier_distance, this x sigma(z))
    min_inlier_distance: float = 0.003
    max_normal_angle_deg: float = 25.0
    min_points: int = 12               # voxels a primitive needs
    cylinders: bool = True
    cylinder_radius_range: tuple[float, float] = (0.008, 0.25)
    ransac_candidates: int = 48        # seeds drawn per round, each giving a plane and a cylinder
    ransac_sample: int = 2000          # unexplained voxels candidates are scored on
    ransac_accept_per_round: int = 6
    ransac_patience: int = 3           # rounds in a row without a new shape before stopping
    max_primitives: int = 64
    null_cost: float = 4.0             # data cost of "no primitive", in squared inlier distances
    max_distance_ratio: float = 2.5    # a label is forbidden beyond this many inlier distances
    smoothness: float = 0.35           # Potts weight of a neighbour pair one voxel apart
    max_passes: int = 3
    adjacency_gap: float = 2.5         # in voxels: closer inliers make primitives neighbours
    mdl_k: float = 2.5e-4              # K of equation 1, per descriptor parameter
    point_check: float = 2.0           # final per-point distance test, in inlier distances

    def __post_init__(self):
        check.positive(self, "voxel_size", "sensor_focal", "inlier_sigmas", "min_inlier_distance", "null_cost",
                       "max_distance_ratio", "adjacency_gap", "point_check")
        check.whole(self, "k_neighbours", "min_points", "ransac_candidates", "ransac_sample",
                    "ransac_accept_per_round", "ransac_patience", "max_primitives", "max_passes")
        check.flag(self, "sensor_noise", "thin_finer", "cylinders")
        check.within(self, "max_normal_angle_deg", low=0, high=90, closed=False)
        lo, hi = check.real_pair(self, "cylinder_radius_range", " with 0 < min < max")
        if not 0 < lo < hi:
            raise InvalidInputError(f"DecomposeParams.cylinder_radius_range must be (min, max) with 0 < min < max, "
                                    f"got {self.cylinder_radius_range!r}")
        check.non_negative(self, "smoothness", "mdl_k")

    @classmethod
    def names(cls) -> list[str]:
        return [f.name for f in fields(cls)]


@dataclass(frozen=True)
class DecompositionStats:
    total_ms: float
    preprocess_ms: float
    hypotheses_ms: float
    graphcut_ms: float
    merge_ms: float
    n_voxels: int
    n_hypotheses: int
    n_merges: int
    n_sampled: int  # finite points the voxels were built from: all, or one a pixel of a finer cloud's


@dataclass(frozen=True, eq=False)
class Decomposition:
    """The result: the primitive shape graph, and labels (N,) int64 giving each
    input point's primitive index, or -1 (no primitive, or a NaN point)."""

    graph: PrimitiveShapeGraph
    labels: np.ndarray
    stats: DecompositionStats

    @property
    def primitives(self) -> tuple[Primitive, ...]:
        return self.graph.primitives


def inlier_threshold(points: np.ndarray, params: DecomposeParams) -> np.ndarray:
    """(N,) inlier distance for each point, metres."""
    if not params.sensor_noise:
        return np.full(len(points), params.min_inlier_distance)
    return np.maximum(params.min_inlier_distance, params.inlier_sigmas * depth_noise().depth_sigma(points[:, 2]))


def decompose(cloud: PointCloud, params: DecomposeParams | None = None,
              rng: np.random.Generator | None = None) -> Decomposition:
    """Decompose `cloud` into planes and cylinders.

    Args:
        cloud: points in metres in the sensor frame (the sensor at the origin);
            NaN rows are allowed and come out labelled -1.
        params: settings; DecomposeParams() by default.
        rng: the only source of randomness; np.random.default_rng(0) by default,
            so equal inputs give equal labels.
    """
    if not isinstance(cloud, PointCloud):
        raise InvalidInputError(f"decompose() takes a psorr.PointCloud, got {type(cloud).__name__}")
    require_sensor_metres(cloud, "decompose(): the cloud")
    if params is None:
        params = DecomposeParams()
    check.require_instance(params, DecomposeParams, "decompose()'s params",
                           "pass DecomposeParams(...), or None for the defaults")
    rng = random_generator(rng, "decompose()")
    clock = [time.perf_counter()]

    def lap():
        clock.append(time.perf_counter())
        return (clock[-1] - clock[-2]) * 1e3

    focal = params.sensor_focal if params.sensor_noise and params.thin_finer else None  # nor are CAD samples
    vox = preprocess(cloud, params.voxel_size, params.k_neighbours, focal)
    threshold = inlier_threshold(vox.points, params)
    edge_i, edge_j, edge_len = undirected_edges(vox)
    t_pre = lap()

    hypotheses, claimed = generate_hypotheses(vox, threshold, params, rng)
    t_hyp = lap()

    labels = _assign(vox, hypotheses, claimed, threshold, (edge_i, edge_j, edge_len), params, rng)
    pieces = _split_components(labels, hypotheses, vox, threshold, (edge_i, edge_j, edge_len), params)
    t_cut = lap()

    cos_max = np.cos(np.radians(params.max_normal_angle_deg))
    gap = params.adjacency_gap * params.voxel_size
    n_merges = merge_greedy(pieces, labels, vox, (edge_i, edge_j, edge_len), threshold, cos_max, gap,
                            params.mdl_k, params.cylinder_radius_range[1])
    graph, point_labels = _finalise(cloud, vox, pieces, labels, (edge_i, edge_j, edge_len), params)
    t_merge = lap()

    stats = DecompositionStats((clock[-1] - clock[0]) * 1e3, t_pre, t_hyp, t_cut, t_merge,
                               len(vox), len(hypotheses), n_merges, vox.n_sampled)
    return Decomposition(graph, point_labels, stats)


def _assign(vox: Voxelized, hypotheses, claimed, threshold, edges, params, rng) -> np.ndarray:
    """Alpha-expansion over the hypotheses plus a "no primitive" label."""
    cos_max = np.cos(np.radians(params.max_normal_angle_deg))
    n_labels = len(hypotheses) + 1
    costs = np.full((len(vox), n_labels), np.inf)
    for h, hyp in enumerate(hypotheses):
        ratio = shapes.distances(hyp.kind, hyp.params, vox.points) / threshold
        agree = shapes.normal_agreement(hyp.kind, hyp.params, vox.points, vox.normals) > cos_max
        allowed = agree & (ratio < params.max_distance_ratio)
        costs[allowed, h] = ratio[allowed] ** 2
    costs[:, -1] = params.null_cost
    edge_i, edge_j, edge_len = edges
    # Potts weights fall with neighbour distance, so depth edges are cheap to cut.
    weights = params.smoothness * params.voxel_size / np.maximum(edge_len, 0.5 * params.voxel_size)
    initial = np.where(claimed >= 0, claimed, n_labels - 1)
    labels, _ = alpha_expansion(costs, edge_i, edge_j, weights, initial, rng, params.max_passes)
    labels[labels == n_labels - 1] = -1
    return labels


def best_fitting_kind(points, normals, threshold, params, preferred=None):
    """(kind, shape params, support count) of the shape that explains the
    oriented points best, or None. A cylinder has three more parameters and
    can imitate a plane with a huge radius, so it must explain clearly more
    (5 %) than the plane does; `preferred` breaks exact ties."""
    cos_max = np.cos(np.radians(params.max_normal_angle_deg))
    fits = {}
    for kind in PrimitiveKind:
        if kind is PrimitiveKind.CYLINDER and not params.cylinders:
            continue
        if kind is PrimitiveKind.CYLINDER and PrimitiveKind.PLANE in fits and \
                fits[PrimitiveKind.PLANE][1] >= 0.97 * len(points):
            continue  # a plane that explains (nearly) everything wins anyway
        fitted = shapes.fit(kind, points, normals, max_radius=params.cylinder_radius_range[1])
        if fitted is not None:
            fits[kind] = (fitted, int(support_mask(kind, fitted, points, normals, threshold, cos_max).sum()))
    if not fits:
        return None
    plane, cylinder = fits.get(PrimitiveKind.PLANE), fits.get(PrimitiveKind.CYLINDER)
    if plane and cylinder:
        margin = 1.05 if preferred is not PrimitiveKind.CYLINDER else 1.0
        kind = PrimitiveKind.CYLINDER if cylinder[1] > margin * plane[1] else PrimitiveKind.PLANE
    else:
        kind = PrimitiveKind.PLANE if plane else PrimitiveKind.CYLINDER
    return kind, fits[kind][0], fits[kind][1]


def _split_components(labels, hypotheses, vox, threshold, edges, params) -> dict[int, Piece]:
    """One piece per connected patch of a label, so coplanar faces of two
    objects become two primitives; patches under min_points are dropped.
    Each patch is refitted with whichever kind explains it best."""
    edge_i, edge_j, edge_len = edges
    same = (labels[edge_i] == labels[edge_j]) & (labels[edge_i] >= 0)
    same &= edge_len < params.adjacency_gap * params.voxel_size
    m = len(labels)
    graph = coo_matrix((np.ones(same.sum()), (edge_i[same], edge_j[same])), shape=(m, m))
    _, component = connected_components(graph, directed=False)
    pieces: dict[int, Piece] = {}
    assigned = np.flatnonzero(labels >= 0)
    order = np.argsort(component[assigned], kind="stable")
    comp_sorted = component[assigned][order]
    bounds = np.flatnonzero(np.r_[True, comp_sorted[1:] != comp_sorted[:-1], True])
    new_labels = np.full(m, -1, dtype=np.int64)
    for start, stop in zip(bounds[:-1], bounds[1:]):
        members = assigned[order[start:stop]]
        if len(members) < params.min_points:
            continue
        hyp = hypotheses[labels[members[0]]]
        for part in _wall_and_bore(hyp, members, vox, params.min_points):
            best = best_fitting_kind(vox.points[part], vox.normals[part], threshold[part], params, hyp.kind)
            kind, fitted = (best[0], best[1]) if best is not None else (hyp.kind, hyp.params)
            piece_id = len(pieces)
            pieces[piece_id] = Piece(kind, tuple(float(v) for v in fitted), part)
            new_labels[part] = piece_id
    labels[:] = new_labels
    return pieces


_MIN_BORE_SHARE = 0.15


def _wall_and_bore(hyp, members, vox, min_points) -> list[np.ndarray]:
    """A cylinder patch split into its outer-wall and bore points when it holds enough of both.

    A cylinder of the radius between a bush's wall and its bore is within reach of both, so the
    graph cut can give them one label; fitted together they give neither radius. A few flipped
    normals along a silhouette are noise, not a bore, and stay where they are."""
    if hyp.kind is not PrimitiveKind.CYLINDER:
        return [members]
    outward = shapes.faces_outward(hyp.params, vox.points[members], vox.normals[members])
    minority = min(outward.sum(), (~outward).sum())
    if minority < max(min_points, _MIN_BORE_SHARE * len(members)):
        return [members]
    return [members[outward], members[~outward]]


_MAX_FIT_POINTS = 20_000


def _finalise(cloud, vox, pieces, labels, edges, params):
    """Map voxel labels back to every input point, keep the points the shape
    explains, refit on them, and build the primitive shape graph."""
    valid = np.flatnonzero(vox.voxel_of >= 0)
    point_labels = np.full(len(cloud), -1, dtype=np.int64)
    point_labels[valid] = labels[vox.voxel_of[valid]]
    # Group point indices by label with one sort rather than a scan per primitive.
    small = max(pieces, default=-1) < np.iinfo(np.int16).max  # 16-bit keys: a radix sort, several times faster
    order = np.argsort(point_labels.astype(np.int16) if small else point_labels, kind="stable")
    bounds = np.searchsorted(point_labels[order], np.arange(max(pieces, default=-1) + 2))
    primitives, remap = [], {}
    for pid in sorted(pieces, key=lambda i: -len(pieces[i].members)):
        piece = pieces[pid]
        idx = order[bounds[pid]:bounds[pid + 1]]
        pts = cloud.points[idx]
        keep = shapes.distances(piece.kind, piece.params, pts) < params.point_check * inlier_threshold(pts, params)
        point_labels[idx[~keep]] = -1
        idx, pts = idx[keep], pts[keep]
        refit, kind = None, piece.kind
        if len(idx) >= 6:
            # An evenly strided 20k points pin a shape down as well as 200k do.
            sub = slice(None, None, max(1, len(idx) // _MAX_FIT_POINTS))
            normals = vox.normals[vox.voxel_of[idx[sub]]]
            refit = shapes.fit(kind, pts[sub], normals, refine=True, max_radius=params.cylinder_radius_range[1])
            if refit is None and kind is PrimitiveKind.CYLINDER:
                # Refined out of the radius range: the patch is flat after all.
                kind, refit = PrimitiveKind.PLANE, shapes.fit_plane(pts[sub], normals)
        if len(idx) < params.min_points or refit is None:
            point_labels[idx] = -1
            continue
        axis = np.asarray(refit[:3] if kind is PrimitiveKind.PLANE else refit[3:6])
        box = box_around_axis(pts, axis, hull_points=vox.points[piece.members])
        remap[pid] = len(primitives)
        primitives.append(Primitive(kind, refit, idx, column_mean(pts), box))
    lookup = np.full(max(pieces, default=-1) + 2, -1, dtype=np.int64)
    for pid, new in remap.items():
        lookup[pid] = new
    point_labels = lookup[point_labels]  # -1 indexes the trailing -1 entry
    pairs = graph_edges(primitives, lookup[labels], vox.points, params.adjacency_gap * params.voxel_size)
    return PrimitiveShapeGraph(tuple(primitives), tuple(pairs)), point_labels
