"""Oriented point-pair features, their frames and the hash table of model pairs.

A pair (p1, n1), (p2, n2) with d = p2 - p1 has the three angles of the
paper's equation 2, angle(n1, d), angle(n2, d) and angle(n1, n2). Those
angles key the table, and |d| is kept in the cell and compared on lookup. The
frame of equation 3 has its origin at p1, x along n1 and y along the part of
d orthogonal to n1. A model pair and a scene pair with equal features give
T_model_scene = F_model @ inv(F_scene).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.checks import params as check
from psorr.errors import InvalidInputError
from psorr.types import PrimitiveKind


def _angle(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    cos = np.einsum("ij,ij->i", u, v) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-12)
    return np.arccos(np.clip(cos, -1.0, 1.0))


def pair_features(p1, n1, p2, n2) -> tuple[np.ndarray, np.ndarray]:
    """(angles (M, 3) radians, distances (M,) metres) of M oriented pairs."""
    d = p2 - p1
    return np.column_stack([_angle(n1, d), _angle(n2, d), _angle(n1, n2)]), np.linalg.norm(d, axis=1)


def pair_frames(p1, n1, p2) -> np.ndarray:
    """(M, 4, 4) frames F (frame -> world): origin p1, x = n1, y = d without its n1 part.
    Pairs whose d is parallel to n1 get an arbitrary but valid y."""
    x = n1 / np.linalg.norm(n1, axis=1, keepdims=True)
    d = p2 - p1
    y = d - np.einsum("ij,ij->i", d, x)[:, None] * x
    length = np.linalg.norm(y, axis=1)
    degenerate = length < 1e-9
    if degenerate.any():
        helper = np.where(np.abs(x[degenerate, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        y[degenerate] = np.cross(x[degenerate], helper)
        length[degenerate] = np.linalg.norm(y[degenerate], axis=1)
    y /= length[:, None]
    frames = np.zeros((len(p1), 4, 4))
    frames[:, :3, 0], frames[:, :3, 1], frames[:, :3, 2] = x, y, np.cross(x, y)
    frames[:, :3, 3] = p1
    frames[:, 3, 3] = 1.0
    return frames


def invert_rigid(T: np.ndarray) -> np.ndarray:
    """Inverse of (..., 4, 4) rigid transforms."""
    R = T[..., :3, :3]
    out = np.zeros_like(T)
    out[..., :3, :3] = np.swapaxes(R, -1, -2)
    out[..., :3, 3] = -np.einsum("...ji,...j->...i", R, T[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


@dataclass(frozen=True)
class HashParams:
    """Quantisation of the table: angle bins in degrees, distance tolerance in metres."""

    angle_step_deg: float = 12.0
    distance_tolerance: float = 0.008
    nearest_neighbour_bins: bool = True  # lookups also probe the adjacent bin nearer each angle

    def __post_init__(self):
        check.positive(self, "angle_step_deg", unit=" degrees")
        if self.angle_step_deg > 90:
            raise InvalidInputError(f"HashParams.angle_step_deg must be at most 90 degrees, got {self.angle_step_deg}")
        check.positive(self, "distance_tolerance", unit=" metres")
        check.flag(self, "nearest_neighbour_bins")

    @property
    def n_bins(self) -> int:
        return int(np.ceil(180.0 / self.angle_step_deg))

    def keys(self, angles: np.ndarray) -> np.ndarray:
        """(M,) int64 cell keys of (M, 3) angle triples."""
        return self._key(self._bins(angles)[1])

    def _bins(self, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(position in bins (M, 3) float, bin index (M, 3) int64) of angle triples."""
        position = np.degrees(angles) / self.angle_step_deg
        return position, np.minimum(position.astype(np.int64), self.n_bins - 1)

    def _key(self, bins: np.ndarray) -> np.ndarray:
        return (bins[..., 0] * self.n_bins + bins[..., 1]) * self.n_bins + bins[..., 2]

    def probe_keys(self, angles: np.ndarray, neighbours: bool | None = None) -> np.ndarray:
        """(M, C) keys a scene pair is looked up under: its own cell, and with neighbours (default:
        nearest_neighbour_bins) every combination with the neighbouring bin nearer each angle (C = 8).
        A scene centroid is seldom where a model sample was drawn, so its angles land a few degrees
        off the model pair's, and across a bin border as often as not."""
        position, bins = self._bins(angles)
        if not (self.nearest_neighbour_bins if neighbours is None else neighbours):
            return self._key(bins)[:, None]
        step = np.where(position - bins < 0.5, -1, 1)
        neighbour = np.clip(bins + step, 0, self.n_bins - 1)
        corners = np.array([[(c >> a) & 1 for a in range(3)] for c in range(8)], bool)  # (8, 3)
        probes = np.where(corners[None], neighbour[:, None, :], bins[:, None, :])  # (M, 8, 3)
        keys = self._key(probes)
        # A clipped neighbour repeats the own bin; repeated keys would return the same rows twice.
        keys.sort(axis=1)
        keys[:, 1:][keys[:, 1:] == keys[:, :-1]] = -1
        return keys


@dataclass(frozen=True, eq=False)
class PairTable:
    """Model pairs sorted by cell key, for lookups by binary search.

    Attributes:
        params: the quantisation.
        points, normals: (P, 3) the library's oriented model points (model frames).
        keys: (E,) cell keys, sorted; distances: (E,) |d| in metres.
        first, second: (E,) indices into points of each stored pair.
        model: (P,) index of the model each oriented point belongs to.
        primitive: (P,) index of the point's primitive within its model.
    """

    params: HashParams
    points: np.ndarray
    normals: np.ndarray
    model: np.ndarray
    primitive: np.ndarray
    keys: np.ndarray
    distances: np.ndarray
    first: np.ndarray
    second: np.ndarray

    @classmethod
    def build(cls, params: HashParams, points, normals, model, primitive, first, second) -> PairTable:
        angles, distances = pair_features(points[first], normals[first], points[second], normals[second])
        keys = params.keys(angles)
        order = np.argsort(keys, kind="stable")
        return cls(params, points, normals, np.asarray(model, np.int32), np.asarray(primitive, np.int32), keys[order],
                   distances[order].astype(np.float32), np.asarray(first, np.int32)[order],
                   np.asarray(second, np.int32)[order])

    def __len__(self) -> int:
        return len(self.keys)

    def lookup(self, p1, n1, p2, n2, neighbours: bool | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Matches for M scene pairs: (scene pair index (K,), table row (K,)), rows in the
        probed cells (see HashParams.probe_keys) whose distance is within the tolerance."""
        angles, distances = pair_features(p1, n1, p2, n2)
        probes = self.params.probe_keys(angles, neighbours)
        keys = probes.ravel()
        lo = np.searchsorted(self.keys, keys, side="left")
        hi = np.where(keys >= 0, np.searchsorted(self.keys, keys, side="right"), lo)
        counts = hi - lo
        scene = np.repeat(np.arange(len(keys)) // probes.shape[1], counts)
        rows = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) + np.repeat(lo, counts)
        close = np.abs(self.distances[rows] - distances[scene]) < self.params.distance_tolerance
        return scene[close], rows[close]

    def poses(self, scene_index, rows, p1, n1, p2) -> tuple[np.ndarray, np.ndarray]:
        """(T_cloud_model (K, 4, 4) = F_scene @ inv(F_model), model index (K,)) for lookup() matches."""
        a, b = self.first[rows], self.second[rows]
        frames_model = pair_frames(self.points[a], self.normals[a], self.points[b])
        frames_scene = pair_frames(p1[scene_index], n1[scene_index], p2[scene_index])
        return frames_scene @ invert_rigid(frames_model), self.model[a]


def scene_oriented_points(primitives, max_extent: float,
                          table: int | None = None) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """PSORR's oriented scene points: plane centroids with normals and cylinder axes (the axis point
    nearest the centroid), as (K, 3) points and (K, 3) directions, and the indices of the K primitives
    they come from. A primitive whose box is longer than ``max_extent`` metres (the table) is skipped, and
    so is the primitive ``table`` indexes, when given."""
    pts, nrm, used = [], [], []
    for index, p in enumerate(primitives):
        if max(p.box.extent) > max_extent or index == table:
            continue
        if p.kind is PrimitiveKind.PLANE:
            pts.append(p.centroid)
            nrm.append(p.normal)
        else:
            pts.append(p.axis_point + ((p.centroid - p.axis_point) @ p.axis) * p.axis)
            nrm.append(p.axis)
        used.append(index)
    return np.array(pts).reshape(-1, 3), np.array(nrm).reshape(-1, 3), used
