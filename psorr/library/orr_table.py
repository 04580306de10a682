"""ORR's own model hash table (Papazov and Burschka, ACCV 2010): dense oriented point pairs of the model
surface at one pair width d.

Each model's surface samples are gathered into leaves of the scene's voxel: one oriented point per
occupied voxel and side (the mean of its samples, so that a wall thinner than a voxel gives a leaf per
face), whose normal is estimated as the scene's points get theirs (the principal axis of the leaves
within 3 voxels), turned outwards. Every ordered pair of leaves whose distance is within the band
d +- delta (delta: half a voxel's diagonal, the spread of a leaf's point in its voxel) is stored under its
pair feature: the three angles angle(n1, p2 - p1), angle(n2, p2 - p1) and angle(n1, n2) key it, in cells
of ``angle_cell_deg``, and its distance is checked on lookup. A lookup probes the scene pair's own cell
(with ``neighbour_cells``, the 26 around it too). Pairs of two leaves on one plane (every angle within one
cell of 90, 90 and 0 degrees) are left out, as Papazov does: a plane gives them everywhere and they fix
no pose. A pose maps the model pair's frame onto the scene pair's: origin at the midpoint, x along the
chord, y along the sum of the normals' parts across it.

The pairs of a model depend only on its surface samples and these settings, so they are cached with the
trained models (psorr.library.cache's folder), keyed by both and by psorr's code; PSORR's training and
its table are untouched.
"""

from __future__ import annotations

import hashlib
import json
import os
import uuid
from dataclasses import asdict, dataclass, fields

import numpy as np
import open3d as o3d
from scipy.spatial import cKDTree

from psorr.checks import params as check
from psorr.library.cache import cache_dir, code_fingerprint
from psorr.library.ppf import HashParams, PairTable, invert_rigid, pair_features

# The 27 cells around a scene pair's cell (itself among them), as bin offsets per angle.
_CUBE = np.array([(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)], dtype=np.int64)


@dataclass(frozen=True)
class OrrTableParams:
    """How ORR's model table is sampled. ``voxel_size`` (m): the leaf size, the scene view's voxel
    (SceneView's ``icp_voxel``), so model and scene leaves are alike. ``pair_width`` is d as a share of the
    library's smallest diameter: Papazov takes d about half the extent of an object's visible part, and
    3/4 of the smallest part's diameter did best (docs/decisions/0048-orr-budget.md). ``angle_cell_deg``:
    the cells' width, his implementation's 60 cells over 180 degrees; ``neighbour_cells``: a lookup probes
    the 26 cells around a scene pair's own too (his later implementation's, which votes before it checks)."""

    voxel_size: float = 0.004
    pair_width: float = 0.75
    angle_cell_deg: float = 3.0
    neighbour_cells: bool = False

    def __post_init__(self):
        check.positive(self, "voxel_size", unit=" metres")
        check.within(self, "pair_width", closed=False)
        check.positive(self, "angle_cell_deg", unit=" degrees")
        check.flag(self, "neighbour_cells")

    @property
    def hashing(self) -> CubeHash:
        """The cells, and the distance tolerance of a lookup: a scene pair and a model pair both in the band."""
        return CubeHash(angle_step_deg=self.angle_cell_deg, distance_tolerance=2 * self.band)

    @property
    def band(self) -> float:
        """delta (m): half a voxel's diagonal."""
        return float(np.sqrt(3) / 2 * self.voxel_size)


@dataclass(frozen=True)
class CubeHash(HashParams):
    """HashParams whose neighbour lookups probe the 3 x 3 x 3 cells around a pair's own cell."""

    def probe_keys(self, angles: np.ndarray, neighbours: bool | None = None) -> np.ndarray:
        _, bins = self._bins(angles)
        if not (self.nearest_neighbour_bins if neighbours is None else neighbours):
            return self._key(bins)[:, None]
        probes = bins[:, None, :] + _CUBE[None]
        keys = self._key(probes)
        keys[((probes < 0) | (probes >= self.n_bins)).any(axis=2)] = -1
        return keys


def coplanar(angles: np.ndarray, tolerance: float) -> np.ndarray:
    """(M,) bool: pairs (angles (M, 3) of pair_features) whose normals both lie across the chord and agree,
    within ``tolerance`` radians."""
    return ((np.abs(angles[:, 0] - np.pi / 2) < tolerance) & (np.abs(angles[:, 1] - np.pi / 2) < tolerance)
            & (angles[:, 2] < tolerance))


def pair_frames(p1, n1, p2, n2) -> np.ndarray:
    """(M, 4, 4) frames (frame -> world) of M oriented pairs: origin at the midpoint, x along p2 - p1, y along
    the sum of the normals' parts across it (n1's alone when they cancel; any normal to x when both do)."""
    x = p2 - p1
    x /= np.maximum(np.linalg.norm(x, axis=1, keepdims=True), 1e-12)
    y = np.zeros_like(x)
    for n in (n1, n2):
        across = n - np.einsum("ij,ij->i", n, x)[:, None] * x
        y += across / np.maximum(np.linalg.norm(across, axis=1, keepdims=True), 1e-12)
    for fallback in (n1 - np.einsum("ij,ij->i", n1, x)[:, None] * x, np.cross(x, [[1.0, 0, 0]]),
                     np.cross(x, [[0, 1.0, 0]])):
        weak = np.linalg.norm(y, axis=1) < 1e-6
        y[weak] = fallback[weak]
    y /= np.linalg.norm(y, axis=1, keepdims=True)
    frames = np.zeros((len(p1), 4, 4))
    frames[:, :3, 0], frames[:, :3, 1], frames[:, :3, 2] = x, y, np.cross(x, y)
    frames[:, :3, 3] = (p1 + p2) / 2
    frames[:, 3, 3] = 1.0
    return frames


def surface_leaves(points: np.ndarray, normals: np.ndarray, voxel: float) -> tuple[np.ndarray, np.ndarray]:
    """One oriented point per occupied voxel and side of the surface samples ``points``, ``normals`` (N, 3):
    the samples' mean, with the normal of the voxels' neighbourhood as the scene's points get theirs, turned
    to the samples' side. A wall thinner than a voxel gives a leaf per face, as the sensor sees either."""
    centres, voxel_of = _means(np.floor(points / voxel).astype(np.int64), points)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(centres))
    cloud.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=3 * voxel, max_nn=20))
    fitted = np.asarray(cloud.normals)[voxel_of]
    back = np.einsum("ij,ij->i", fitted, normals) < 0
    leaves, leaf_of = _means(np.column_stack([voxel_of, back]), points)
    side = np.zeros(len(leaves))
    side[leaf_of] = np.where(back, -1.0, 1.0)
    leaf_normals = np.zeros_like(leaves)
    leaf_normals[leaf_of] = fitted * side[leaf_of, None]
    return leaves, leaf_normals


def _means(labels: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(mean of ``points`` (N, 3) per distinct row of ``labels`` (N,) or (N, k), the group of each point (N,))."""
    _, group, counts = np.unique(labels.reshape(len(labels), -1), axis=0, return_inverse=True, return_counts=True)
    group = group.ravel()
    sums = np.zeros((len(counts), 3))
    np.add.at(sums, group, points)
    return sums / counts[:, None], group


@dataclass(frozen=True, eq=False)
class ModelPairs:
    """One model's part of ORR's table: its leaves (L, 3) and their normals (L, 3), and its stored pairs as
    leaf indices ``first``, ``second`` (E,) with their cell ``keys`` (E,) and ``distances`` (E,) in metres."""

    leaves: np.ndarray
    normals: np.ndarray
    first: np.ndarray
    second: np.ndarray
    keys: np.ndarray
    distances: np.ndarray


def model_pairs(points: np.ndarray, normals: np.ndarray, width: float, params: OrrTableParams) -> ModelPairs:
    """The leaves of a model's surface samples ``points``, ``normals`` (N, 3) and every ordered pair of them
    ``width`` +- band apart, less the coplanar ones."""
    leaves, leaf_normals = surface_leaves(points, normals, params.voxel_size)
    close = cKDTree(leaves).query_pairs(width + params.band, output_type="ndarray")
    i, j = close[:, 0], close[:, 1]
    keep = np.linalg.norm(leaves[j] - leaves[i], axis=1) >= width - params.band
    first, second = np.concatenate([i[keep], j[keep]]), np.concatenate([j[keep], i[keep]])
    angles, distances = pair_features(leaves[first], leaf_normals[first], leaves[second], leaf_normals[second])
    keep = ~coplanar(angles, np.radians(params.angle_cell_deg))
    return ModelPairs(leaves, leaf_normals, first[keep].astype(np.int32), second[keep].astype(np.int32),
                      params.hashing.keys(angles[keep]), distances[keep].astype(np.float32))


class OrrTable:
    """ORR's model table of a library: every model's leaves and dense pairs in one PairTable (keyed as
    OrrTableParams.hashing says), the pair width ``width`` (m) they were drawn at, and each model's leaf count."""

    def __init__(self, table: PairTable, width: float, params: OrrTableParams, leaves: np.ndarray):
        self.table, self.width, self.params, self.leaves = table, width, params, leaves

    @classmethod
    def for_library(cls, library, params: OrrTableParams, use_cache: bool = True) -> OrrTable:
        """The table of ``library``'s models (a ModelLibrary), each model's pairs from the cache when held."""
        width = params.pair_width * min(m.diameter for m in library.models)
        parts = [_cached_pairs(model, width, params, use_cache) for model in library.models]
        offsets = np.cumsum([0] + [len(p.leaves) for p in parts])
        keys = np.concatenate([p.keys for p in parts])
        order = np.argsort(keys, kind="stable")
        owner = np.repeat(np.arange(len(parts), dtype=np.int32), np.diff(offsets))
        first = np.concatenate([p.first + o for p, o in zip(parts, offsets)])
        second = np.concatenate([p.second + o for p, o in zip(parts, offsets)])
        table = PairTable(params.hashing, np.vstack([p.leaves for p in parts]), np.vstack([p.normals for p in parts]),
                          owner, np.zeros_like(owner), keys[order], np.concatenate([p.distances for p in parts])[order],
                          first[order].astype(np.int32), second[order].astype(np.int32))
        return cls(table, width, params, np.diff(offsets))

    def __len__(self) -> int:
        return len(self.table)

    def poses(self, p1, n1, p2, n2) -> tuple[np.ndarray, np.ndarray]:
        """(T_cloud_model (K, 4, 4), model index (K,)) of every stored pair in the cell of each of M scene
        pairs (points p1, p2 and normals n1, n2, (M, 3) each; with neighbour_cells, in the 27 around it)."""
        scene, rows = self.table.lookup(p1, n1, p2, n2, neighbours=self.params.neighbour_cells)
        t = self.table
        a, b = t.first[rows], t.second[rows]
        frames_model = pair_frames(t.points[a], t.normals[a], t.points[b], t.normals[b])
        frames_scene = pair_frames(p1[scene], n1[scene], p2[scene], n2[scene])
        return frames_scene @ invert_rigid(frames_model), t.model[a]


def _cached_pairs(model, width: float, params: OrrTableParams, use_cache: bool) -> ModelPairs:
    """model_pairs() of ``model``, read from or kept in the training cache's folder."""
    digest = hashlib.sha256()
    for array in (model.points, model.normals):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    digest.update(json.dumps([width, asdict(params), code_fingerprint()]).encode())
    path = cache_dir() / f"{model.name}-orr-{digest.hexdigest()[:24]}.npz"
    if use_cache and path.is_file():
        try:
            with np.load(path) as data:
                return ModelPairs(**{f.name: data[f.name] for f in fields(ModelPairs)})
        except Exception:  # noqa: BLE001  a torn or foreign entry is rebuilt, as a training entry is retrained
            pass
    pairs = model_pairs(model.points, model.normals, width, params)
    if use_cache:
        _store(path, {f.name: getattr(pairs, f.name) for f in fields(ModelPairs)})
    return pairs


def _store(path, arrays: dict) -> None:
    """Write ``arrays`` to ``path`` whole or not at all; a cache that cannot be written is passed over."""
    tmp = path.with_name(f"{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "xb") as f:
            np.savez(f, **arrays)
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
