"""A triangle mesh's surface moments, exact per triangle: its area centroid and its second moments about it.

Every rotation that maps a surface onto itself fixes both, so they are what a search for symmetries starts
from (:mod:`psorr.synthetic.mesh_symmetry`) and what tells two poses of a part apart without rendering
(:mod:`psorr.hypotheses.same_surface`).
"""

from __future__ import annotations

import numpy as np


def _triangles(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    triangles = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    areas = 0.5 * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]),
                                 axis=1)
    return triangles, areas


def surface_area(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The area of the surface of (V, 3) ``vertices`` and (F, 3) ``faces`` (the vertices' unit squared)."""
    return float(_triangles(vertices, faces)[1].sum())


def area_centroid(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(3,) the centroid of the surface of (V, 3) ``vertices`` and (F, 3) ``faces``, weighted by triangle area."""
    return _centroid(*_triangles(vertices, faces))


def second_moments(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(3, 3) the surface's second moments about its area centroid, per unit area (the points' unit squared):
    the mean of x x^T over the surface, exactly per triangle."""
    triangles, areas = _triangles(vertices, faces)
    triangles = triangles - _centroid(triangles, areas)
    corners = np.einsum("fki,fkj->fij", triangles, triangles)
    total = triangles.sum(axis=1)
    per_triangle = (corners + np.einsum("fi,fj->fij", total, total)) / 12.0
    return np.einsum("f,fij->ij", areas, per_triangle) / areas.sum()


def _centroid(triangles: np.ndarray, areas: np.ndarray) -> np.ndarray:
    return np.average(triangles.mean(axis=1), axis=0, weights=areas)
