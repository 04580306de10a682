"""Two-plane cliques (edges) of every model, indexed once in both vertex orders, and matched to a scene's
edges in one vectorised pass.

A part seen from above often shows two of its faces and no third one that spans space with them: an
L bracket's upright and base, a channel's web and a flange. Two adjacent planes that are not parallel
fix the rotation and the position across their common line. The position along the line comes from
the faces themselves: the middle of the two faces' box centres, projected onto the line. The faces
seen may be cut short by occlusion, which shifts that middle; refinement takes it from there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.types import Primitive, PrimitiveKind, PrimitiveShapeGraph

MIN_CROSS = 0.3  # |n_a x n_b| of two unit normals: under it, the planes are too near parallel for a line


@dataclass(frozen=True, eq=False)
class EdgeSet:
    """Edges of one graph, in both vertex orders: vertices (E, 2) plane indices, angle (E,) degrees between
    the normals, normals (E, 2, 3) and the point (E, 3) on the common line nearest the faces' middle."""

    vertices: np.ndarray
    angle: np.ndarray
    normals: np.ndarray
    point: np.ndarray

    @classmethod
    def of(cls, graph: PrimitiveShapeGraph, allowed: set[int] | None = None) -> EdgeSet:
        prims = graph.primitives
        rows = [(i, j) for i, j in graph.edges if _plane(prims[i]) and _plane(prims[j])
                and (allowed is None or {i, j} <= allowed)]
        rows = [r for r in rows if np.linalg.norm(np.cross(prims[r[0]].normal, prims[r[1]].normal)) >= MIN_CROSS]
        rows += [(j, i) for i, j in rows]
        if not rows:
            return cls(np.zeros((0, 2), dtype=np.int64), np.zeros(0), np.zeros((0, 2, 3)), np.zeros((0, 3)))
        vertices = np.array(rows, dtype=np.int64)
        normals = np.array([[prims[i].normal, prims[j].normal] for i, j in rows])
        offsets = np.array([[prims[i].offset, prims[j].offset] for i, j in rows])
        middles = np.array([(prims[i].box.center + prims[j].box.center) / 2 for i, j in rows])
        cos = np.clip(np.einsum("ki,ki->k", normals[:, 0], normals[:, 1]), -1.0, 1.0)
        return cls(vertices, np.degrees(np.arccos(cos)), normals, _nearest_on_line(normals, offsets, middles))

    def __len__(self) -> int:
        return len(self.vertices)


def _plane(p: Primitive) -> bool:
    return p.kind is PrimitiveKind.PLANE


def _nearest_on_line(normals: np.ndarray, offsets: np.ndarray, near: np.ndarray) -> np.ndarray:
    """(E, 3): the point of each line where two planes (normals (E, 2, 3), offsets (E, 2)) meet nearest
    to ``near`` (E, 3): the planes' equations and the direction along the line, solved together."""
    direction = np.cross(normals[:, 0], normals[:, 1])
    A = np.concatenate([normals, direction[:, None]], axis=1)
    b = np.column_stack([-offsets, np.einsum("ki,ki->k", direction, near)])
    return np.linalg.solve(A, b[..., None])[..., 0]


@dataclass(frozen=True, eq=False)
class EdgeMatches:
    """poses (K, 4, 4) T_cloud_model, owners (K,) model indices, scene (K, 2) and model (K, 2) vertices."""

    poses: np.ndarray
    owners: np.ndarray
    scene_vertices: np.ndarray
    model_vertices: np.ndarray


class EdgeIndex:
    """Every model's edges, stacked: the EdgeSet rows with owners (P,)."""

    def __init__(self, models):
        sets = [EdgeSet.of(m.graph) for m in models]
        self.owners = np.concatenate([np.full(len(s), k, dtype=np.int64) for k, s in enumerate(sets)] or
                                     [np.zeros(0, dtype=np.int64)])
        self.vertices = np.concatenate([s.vertices for s in sets]).reshape(-1, 2)
        self.angle = np.concatenate([s.angle for s in sets])
        self.normals = np.concatenate([s.normals for s in sets]).reshape(-1, 2, 3)
        self.point = np.concatenate([s.point for s in sets]).reshape(-1, 3)
        self._order = np.argsort(self.angle, kind="stable")

    def match(self, scene: EdgeSet, angle_tolerance: float, allowed=None) -> EdgeMatches:
        """The poses of every model edge whose angle lies within ``angle_tolerance`` degrees of a scene
        edge's: the normals carried onto the scene's, the line's point onto its point. ``allowed``
        (scene vertices (K, 2), owners (K,), model vertices (K, 2)) -> (K,) bool drops matches first."""
        sorted_angle = self.angle[self._order]
        low = np.searchsorted(sorted_angle, scene.angle - angle_tolerance, side="left")
        high = np.searchsorted(sorted_angle, scene.angle + angle_tolerance, side="right")
        q = np.repeat(np.arange(len(scene)), high - low)
        m = self._order[np.concatenate([np.arange(a, b) for a, b in zip(low, high)] or [np.zeros(0, dtype=np.int64)])]
        if allowed is not None and len(q):
            keep = allowed(scene.vertices[q], self.owners[m], self.vertices[m])
            q, m = q[keep], m[keep]
        poses = np.repeat(np.eye(4)[None], len(q), axis=0)
        if len(q):
            R = np.einsum("kij,klj->kil", _frames(scene.normals[q]), _frames(self.normals[m]))
            poses[:, :3, :3] = R
            poses[:, :3, 3] = scene.point[q] - np.einsum("kij,kj->ki", R, self.point[m])
        return EdgeMatches(poses, self.owners[m], scene.vertices[q], self.vertices[m])


def _frames(normals: np.ndarray) -> np.ndarray:
    """(K, 3, 3) right-handed frames, columns: the bisector of the two normals (K, 2, 3), the direction
    from the first to the second, and their cross product. A model edge's frame carried onto a scene
    edge's splits the difference of their angles evenly between the two normals."""
    middle = normals[:, 0] + normals[:, 1]
    middle /= np.linalg.norm(middle, axis=1, keepdims=True)
    across = normals[:, 1] - normals[:, 0]
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    return np.stack([middle, across, np.cross(middle, across)], axis=2)
