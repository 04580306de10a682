"""Solid primitives for build_workpieces.py, in millimetres: prisms, cylinders, boxes, booleans (manifold3d)
and exact axis turns. Kept apart so the part drawings read on their own."""

from __future__ import annotations

import math

import manifold3d as m3
import numpy as np

N_ROUND = 48  # facets on part-sized cylinders
N_HOLE = 24  # facets on small holes
COS_HALF = math.cos(math.pi / N_ROUND)  # apothem / radius of an N_ROUND-gon
MM = 1e-3



def _circle(r, n=N_ROUND, cx=0.0, cy=0.0):
    # Half-step offset puts a flat facet (not a vertex) on each axis, so grasp
    # rays along x or y hit the middle of a face and widths are the apothem.
    a = (np.arange(n) + 0.5) * (2.0 * np.pi / n)
    return np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)])


def _prism(polygon, z0, z1):
    return m3.Manifold.extrude(m3.CrossSection([np.asarray(polygon, float)]), z1 - z0).translate((0.0, 0.0, z0))


def _cyl(r, z0, z1, cx=0.0, cy=0.0, n=N_ROUND):
    return _prism(_circle(r, n, cx, cy), z0, z1)


def _box(lo, hi):
    lo = np.asarray(lo, float)
    return m3.Manifold.cube(tuple(np.asarray(hi, float) - lo)).translate(tuple(lo))


# Cyclic axis permutations (proper rotations, exact in floating point) that turn
# a solid built along z into one along x or y; local (u, v, w) -> world.
_ALONG = {
    "x": np.array([[0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 0]], float),  # x=w, y=u, z=v
    "y": np.array([[0, 1, 0, 0], [0, 0, 1, 0], [1, 0, 0, 0]], float),  # x=v, y=w, z=u
}


def _along(solid, axis):
    return solid.transform(_ALONG[axis])


def _union(*solids):
    return m3.Manifold.batch_boolean(list(solids), m3.OpType.Add)


def _cut(solid, *tools):
    return solid - _union(*tools)


def _rot(axis, deg, pivot_mm=(0.0, 0.0, 0.0)):
    """4x4 rotation by `deg` about `axis` through `pivot_mm` (millimetres, output in metres)."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rot = c * np.eye(3) + s * k + (1 - c) * np.outer(axis, axis)
    rot[np.abs(rot) < 1e-15] = 0.0
    t = np.eye(4)
    t[:3, :3] = rot
    pivot = np.asarray(pivot_mm, float) * MM
    t[:3, 3] = pivot - rot @ pivot
    return t
