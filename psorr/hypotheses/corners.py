"""Three-plane cliques (corners) of every model, indexed once in all six vertex orders, and matched to a
scene's corners in one vectorised pass: a k-d tree over the normal-to-normal angles, then a batched
Kabsch fit of the normals and the planes' common points."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from psorr.geometry.rotations import kabsch_rotations
from psorr.hypotheses.cliques import Clique, CliqueKind

# (o0-o1, o1-o2, o0-o2) of a vertex order o, as indices into a clique's feature (0-1, 1-2, 0-2).
_ORDERS = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
_PAIR = {(0, 1): 0, (1, 2): 1, (0, 2): 2}


def _permuted_feature(feature: np.ndarray, order: tuple[int, int, int]) -> np.ndarray:
    return np.array([feature[_PAIR[tuple(sorted((order[x], order[y])))]] for x, y in ((0, 1), (1, 2), (0, 2))])


def _corner_arrays(prims, vertex_rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normals (K, 3, 3) and common points (K, 3) of the planes ``vertex_rows`` (K, 3) of ``prims``."""
    normal = np.array([p.normal if p.kind.value == "plane" else np.zeros(3) for p in prims]).reshape(-1, 3)
    offset = np.array([p.offset if p.kind.value == "plane" else 0.0 for p in prims])
    normals = normal[vertex_rows]
    return normals, np.linalg.solve(normals, -offset[vertex_rows][..., None])[..., 0]


@dataclass(frozen=True, eq=False)
class CornerMatches:
    """poses (K, 4, 4) T_cloud_model, owners (K,) model indices, and the matched vertices: scene (K, 3) and
    model (K, 3) primitive indices, row by row in correspondence."""

    poses: np.ndarray
    owners: np.ndarray
    scene_vertices: np.ndarray
    model_vertices: np.ndarray


class CornerIndex:
    """Every model corner in its six vertex orders: features (P, 3) in degrees, owners (P,), vertices
    (P, 3), normals (P, 3, 3) and common points (P, 3)."""

    def __init__(self, models, model_cliques: list[list[Clique]]):
        features, owners, vertices = [], [], []
        normals, points = [np.zeros((0, 3, 3))], [np.zeros((0, 3))]
        for index, (model, cliques) in enumerate(zip(models, model_cliques)):
            corners = [c for c in cliques if c.kind is CliqueKind.PLANES]
            rows = [tuple(c.vertices[k] for k in order) for c in corners for order in _ORDERS]
            if not rows:
                continue
            features += [_permuted_feature(c.feature, order) for c in corners for order in _ORDERS]
            owners += [index] * len(rows)
            vertices += rows
            n, x = _corner_arrays(model.graph.primitives, np.array(rows))
            normals.append(n)
            points.append(x)
        self.features = np.array(features).reshape(-1, 3)
        self.owners = np.array(owners, dtype=np.int64)
        self.vertices = np.array(vertices, dtype=np.int64).reshape(-1, 3)
        self.normals, self.points = np.concatenate(normals), np.concatenate(points)
        self.tree = cKDTree(self.features) if len(self.features) else None

    def match(self, corners: list[Clique], prims, angle_tolerance: float, allowed=None) -> CornerMatches:
        """The poses of every model corner whose angles lie within ``angle_tolerance`` degrees of a scene
        corner's, and whose turned normals do too (a mirrored order fits no rotation). ``allowed`` (scene
        vertices (K, 3), owners (K,), model vertices (K, 3)) -> (K,) bool drops matches first."""
        empty = CornerMatches(np.zeros((0, 4, 4)), np.zeros(0, dtype=np.int64), np.zeros((0, 3), dtype=np.int64),
                              np.zeros((0, 3), dtype=np.int64))
        if not corners or self.tree is None:
            return empty
        scene_rows = np.array([c.vertices for c in corners], dtype=np.int64)
        hits = self.tree.query_ball_point(np.array([c.feature for c in corners]), angle_tolerance, p=np.inf)
        q = np.repeat(np.arange(len(corners)), [len(h) for h in hits])
        m = np.concatenate([np.asarray(h, dtype=np.int64) for h in hits]) if len(q) else np.zeros(0, dtype=np.int64)
        if allowed is not None and len(q):
            keep = allowed(scene_rows[q], self.owners[m], self.vertices[m])
            q, m = q[keep], m[keep]
        if len(q) == 0:
            return empty
        scene_normals, scene_points = _corner_arrays(prims, scene_rows)
        model_normals = self.normals[m]
        R = kabsch_rotations(model_normals, scene_normals[q])
        turned = np.einsum("kij,klj->kli", R, model_normals)
        fits = (np.einsum("kli,kli->kl", turned, scene_normals[q]) >= np.cos(np.radians(angle_tolerance))).all(axis=1)
        q, m, R = q[fits], m[fits], R[fits]
        poses = np.repeat(np.eye(4)[None], len(q), axis=0)
        poses[:, :3, :3] = R
        poses[:, :3, 3] = scene_points[q] - np.einsum("kij,kj->ki", R, self.points[m])
        return CornerMatches(poses, self.owners[m], scene_rows[q], self.vertices[m])
