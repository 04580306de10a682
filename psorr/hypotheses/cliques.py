"""Minimal cliques of a primitive shape graph, and the poses that matching them gives (the paper's
second recognizer, section 2.2).

Two kinds of clique fix a pose on their own:

- three mutually adjacent planes whose normals span space (a box's corner): the feature is the three
  pairwise angles between the normals, in the clique's vertex order; psorr.hypotheses.corners matches
  them, all models' at once, and poses them by the normals and the planes' common point;
- a plane and an adjacent cylinder, matched and posed here: the feature is the cylinder's radius and
  the angle between the plane's normal and the axis; the pose aligns the normal, the axis and the axis
  line, and takes the position along the axis from where the axis meets the plane, or, for an axis
  along the plane, from the cylinders' box centres.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from psorr.types import Primitive, PrimitiveKind, PrimitiveShapeGraph

_MIN_SPAN = 0.3  # |det| of three unit normals: under it, two of the planes are nearly parallel


class CliqueKind(StrEnum):
    PLANES = "three planes"
    PLANE_CYLINDER = "plane and cylinder"


@dataclass(frozen=True, eq=False)
class Clique:
    """vertices: primitive indices (three planes; or the plane, then the cylinder); feature: the three
    normals' pairwise angles in degrees (vertices 0-1, 1-2, 0-2), or (radius in metres, the
    normal-to-axis angle in degrees, folded into [0, 90])."""

    kind: CliqueKind
    vertices: tuple[int, ...]
    feature: np.ndarray


def _angle(u: np.ndarray, v: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip(u @ v, -1.0, 1.0))))


def _plane_triangle(prims, a: int, b: int, c: int) -> Clique | None:
    normals = np.array([prims[k].normal for k in (a, b, c)])
    if abs(np.linalg.det(normals)) < _MIN_SPAN:
        return None
    feature = np.array([_angle(normals[0], normals[1]), _angle(normals[1], normals[2]), _angle(normals[0], normals[2])])
    return Clique(CliqueKind.PLANES, (a, b, c), feature)


def graph_cliques(graph: PrimitiveShapeGraph) -> list[Clique]:
    """Every clique of ``graph`` that fixes a pose: plane triangles whose normals span space, and adjacent
    plane-cylinder pairs."""
    prims = graph.primitives
    neighbours = {k: set() for k in range(len(prims))}
    for i, j in graph.edges:
        neighbours[i].add(j)
        neighbours[j].add(i)
    planes = [k for k, p in enumerate(prims) if p.kind is PrimitiveKind.PLANE]
    out = []
    for a in planes:
        for b in sorted(n for n in neighbours[a] if n > a and prims[n].kind is PrimitiveKind.PLANE):
            for c in sorted(n for n in neighbours[a] & neighbours[b] if n > b and prims[n].kind is PrimitiveKind.PLANE):
                clique = _plane_triangle(prims, a, b, c)
                if clique is not None:
                    out.append(clique)
        for c in sorted(n for n in neighbours[a] if prims[n].kind is PrimitiveKind.CYLINDER):
            tilt = _angle(prims[a].normal, prims[c].axis)
            out.append(Clique(CliqueKind.PLANE_CYLINDER, (a, c),
                              np.array([prims[c].radius, min(tilt, 180.0 - tilt)])))
    return out


def cylinder_match(scene: Clique, model: Clique, angle_tol: float, radius_tol: float) -> bool:
    """Do two plane-and-cylinder cliques match: the radii within ``radius_tol`` of the model's, the
    normal-to-axis angles within ``angle_tol`` degrees?"""
    radius_ok = abs(scene.feature[0] - model.feature[0]) <= radius_tol * model.feature[0]
    return bool(radius_ok and abs(scene.feature[1] - model.feature[1]) <= angle_tol)


def cylinder_poses(scene: list[Primitive], model: list[Primitive]) -> list[np.ndarray]:
    """The two poses (4, 4) T_cloud_model (the axis either way) that carry the model's plane and cylinder
    (in that order) onto the scene's."""
    (plane_s, cyl_s), (plane_m, cyl_m) = scene, model
    poses = []
    for sign in (1.0, -1.0):
        axis_s = sign * cyl_s.axis
        frame_m = _frame(plane_m.normal, cyl_m.axis)
        frame_s = _frame(plane_s.normal, axis_s)
        if frame_m is None or frame_s is None:  # an axis along the normal: any turn about it fits
            frame_m = _frame(cyl_m.axis, _any_normal(cyl_m.axis))
            frame_s = _frame(axis_s, _any_normal(axis_s))
        R = frame_s @ frame_m.T
        # The axis lines first, then the position along the axis.
        t = cyl_s.axis_point - R @ cyl_m.axis_point
        along = axis_s @ plane_s.normal
        if abs(along) > _MIN_SPAN:  # the axis meets the plane: put the model's meeting point on the scene's
            t = _meet(plane_s, cyl_s) - R @ _meet(plane_m, cyl_m)
        else:
            t += axis_s * (axis_s @ (cyl_s.box.center - (R @ cyl_m.box.center + t)))
        poses.append(_pose(R, t))
    return poses


def _meet(plane: Primitive, cylinder: Primitive) -> np.ndarray:
    """Where the cylinder's axis meets the plane."""
    s = -(plane.normal @ cylinder.axis_point + plane.offset) / (plane.normal @ cylinder.axis)
    return cylinder.axis_point + s * cylinder.axis


def _frame(first: np.ndarray, second: np.ndarray) -> np.ndarray | None:
    """(3, 3) right-handed frame with ``first`` as its x axis and ``second``'s part across it in the xy
    plane; None when the two are parallel (a turn about a nearly parallel pair is as good as any)."""
    y = second - (second @ first) * first
    if np.linalg.norm(y) < 1e-9:
        return None
    y /= np.linalg.norm(y)
    return np.column_stack([first, y, np.cross(first, y)])


def _any_normal(v: np.ndarray) -> np.ndarray:
    helper = np.eye(3)[int(np.argmin(np.abs(v)))]
    return np.cross(v, helper) / np.linalg.norm(np.cross(v, helper))


def _pose(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T
