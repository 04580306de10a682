"""Overlap of oriented boxes, used to verify pose hypotheses cheaply.

A hypothesis is checked by moving the minimum-volume boxes of the model's
primitives into the scene and intersecting them with the scene primitives'
boxes (PSORR paper, section 2.1.4). The intersection of two boxes is the convex
hull of box A's vertices inside B, B's vertices inside A, and the points where
each box's edges cross the other's faces: every vertex of the intersection
polytope lies on three face planes, and whichever box owns two (or three) of
them contributes an edge (or a vertex) of its own. Clipping each of the 24
edges to the other box's slabs (Liang-Barsky) yields exactly those points.

All lengths are metres, volumes cubic metres. Boxes are assumed to have an
orthonormal rotation (as built by psorr.geometry.boxes); that is not re-checked per call
because this runs for thousands of pairs per scene.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from psorr.errors import InvalidInputError
from psorr.types import OrientedBox

# Slack in metres for "inside" and "separated": far above the rounding of coordinates
# of a few metres (~1e-15 m), so that faces sharing a plane are not lost to rounding,
# and small enough that the volume it can add (slack x surface area) is negligible.
_TOL = 1e-11

# Corner signs in the order of OrientedBox.corners() (index = 4*ix + 2*iy + iz).
_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
# The 12 edges as corner-index pairs: those that differ in exactly one sign.
_EDGES = np.array([(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1])
_EDGE_START, _EDGE_END = _EDGES[:, 0].copy(), _EDGES[:, 1].copy()
_LOW_HIGH = np.array([-1.0, 1.0])[:, None, None, None]  # the two sides of each slab
_NEXT, _NEXT2 = np.array([1, 2, 0]), np.array([2, 0, 1])


def transform_box(box: OrientedBox, T: np.ndarray) -> OrientedBox:
    """The box moved by a rigid (4, 4) transform T (metres); the extent is unchanged.

    Raises InvalidInputError unless T is finite, rigid (orthonormal with
    determinant +1) and has last row 0 0 0 1.
    """
    T = np.asarray(T, dtype=np.float64)
    if T.shape != (4, 4) or not np.isfinite(T).all():
        raise InvalidInputError(f"T must be a finite (4, 4) array, got shape {T.shape}")
    R = T[:3, :3]
    if (not np.allclose(T[3], (0, 0, 0, 1)) or not np.allclose(R @ R.T, np.eye(3), atol=1e-6)
            or np.linalg.det(R) < 0):
        raise InvalidInputError("T must be a rigid transform (rotation with det +1, last row 0 0 0 1)")
    return OrientedBox(center=R @ box.center + T[:3, 3], rotation=R @ box.rotation, extent=box.extent)


def boxes_to_arrays(boxes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stack a sequence of N boxes into centres (N, 3), rotations (N, 3, 3) and extents (N, 3)."""
    boxes = list(boxes)
    if not boxes:
        return np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros((0, 3))
    return (np.array([b.center for b in boxes]), np.array([b.rotation for b in boxes]),
            np.array([b.extent for b in boxes]))


def _sat_separated(t: np.ndarray, R: np.ndarray, ha: np.ndarray, hb: np.ndarray) -> np.ndarray:
    """Separating-axis test on batches: (...) bool, True where the boxes are disjoint.

    t (..., 3) is B's centre and R (..., 3, 3) B's axes (columns), both in A's
    frame; ha, hb (..., 3) are half extents in m. The 15 candidate axes are A's
    3, B's 3 and the 9 cross products A_i x B_j, whose projections are written
    with entries of R (Gottschalk's closed form). The cross axes are left
    unnormalised, so the fixed slack _TOL grows as _TOL / |A_i x B_j| on them:
    an axis from (nearly) parallel edges, whose projections are pure rounding
    noise, can then never separate; the face axes cover that case.
    """
    absR = np.abs(R)
    sep = (np.abs(t) > ha + (absR @ hb[..., None])[..., 0] + _TOL).any(-1)
    tb = (t[..., None, :] @ R)[..., 0, :]  # B's centre offset along B's axes
    sep |= (np.abs(tb) > (ha[..., None, :] @ absR)[..., 0, :] + hb + _TOL).any(-1)
    # (..., i, j): with i1, i2 = i+1, i+2 (mod 3), A_i x B_j = -R[i2, j] A_i1 + R[i1, j] A_i2.
    i1, i2 = _NEXT, _NEXT2
    dist = np.abs(t[..., i2, None] * R[..., i1, :] - t[..., i1, None] * R[..., i2, :])
    ra = ha[..., i1, None] * absR[..., i2, :] + ha[..., i2, None] * absR[..., i1, :]
    rb = hb[..., None, i1] * absR[..., :, i2] + hb[..., None, i2] * absR[..., :, i1]
    return sep | (dist > ra + rb + _TOL).any((-1, -2))


def boxes_may_overlap(box_a: OrientedBox, box_b: OrientedBox) -> bool:
    """False only if the boxes are disjoint (a separating axis exists among the 15).

    True when the closed boxes intersect, touching faces, edges or corners
    included (their intersection volume is then 0), and also for boxes apart
    by less than the 1e-11 m slack (more when the only separating direction is
    the cross product of nearly parallel edges, see _sat_separated); then too
    intersection_volume gives 0.
    """
    Ra = box_a.rotation
    t = (box_b.center - box_a.center) @ Ra
    return not bool(_sat_separated(t, Ra.T @ box_b.rotation, box_a.extent / 2, box_b.extent / 2))


def overlap_candidates(centers_a, rotations_a, extents_a, centers_b, rotations_b, extents_b,
                       mask: np.ndarray | None = None) -> np.ndarray:
    """(Na, Nb) bool: True where box i of A and box j of B may overlap.

    Centres (N, 3) m, rotations (N, 3, 3) with axes as columns, extents (N, 3)
    full side lengths in m (see boxes_to_arrays). Pairs whose bounding spheres
    are apart are rejected first; the rest get the same exact separating-axis
    test as boxes_may_overlap, so the result equals it pair by pair. Where an
    (Na, Nb) bool ``mask`` is given, only its pairs are tested (the rest are False).
    """
    ca, Ra, ea = (np.asarray(x, float) for x in (centers_a, rotations_a, extents_a))
    cb, Rb, eb = (np.asarray(x, float) for x in (centers_b, rotations_b, extents_b))
    for name, c, R, e in (("a", ca, Ra, ea), ("b", cb, Rb, eb)):
        n = len(c) if c.ndim else -1
        if c.shape != (n, 3) or R.shape != (n, 3, 3) or e.shape != (n, 3):
            raise InvalidInputError(f"set {name} needs centers (N, 3), rotations (N, 3, 3) and extents (N, 3); "
                                    f"got {c.shape}, {R.shape}, {e.shape}")
    if mask is not None and np.shape(mask) != (len(ca), len(cb)):
        raise InvalidInputError(f"mask must be ({len(ca)}, {len(cb)}) bool, got shape {np.shape(mask)}")
    radius_a = np.linalg.norm(ea, axis=1) / 2
    radius_b = np.linalg.norm(eb, axis=1) / 2
    if mask is None:
        d = cb[None, :, :] - ca[:, None, :]  # (Na, Nb, 3)
        result = np.linalg.norm(d, axis=2) <= radius_a[:, None] + radius_b[None, :] + _TOL
        ia, ib = np.nonzero(result)
        d = d[ia, ib]
    else:
        ia, ib = np.nonzero(mask)
        d = cb[ib] - ca[ia]
        near = np.linalg.norm(d, axis=1) <= radius_a[ia] + radius_b[ib] + _TOL
        ia, ib, d = ia[near], ib[near], d[near]
        result = np.zeros((len(ca), len(cb)), dtype=bool)
    if len(ia):
        # SAT only on the pairs the sphere test kept: usually a small share.
        RaT = np.swapaxes(Ra[ia], 1, 2)
        t = (RaT @ d[:, :, None])[:, :, 0]
        result[ia, ib] = ~_sat_separated(t, RaT @ Rb[ib], ea[ia] / 2, eb[ib] / 2)
    return result


def _check_box(box: OrientedBox, name: str) -> tuple[float, float]:
    """(volume m^3, thinnest side m) of a box after checking it; Python floats, as numpy is slow on 3 numbers."""
    e0, e1, e2 = box.extent.tolist()
    c0, c1, c2 = box.center.tolist()
    thinnest = min(e0, e1, e2)
    # A NaN or inf anywhere makes the sum non-finite.
    if not (thinnest >= 0.0 and math.isfinite(e0 + e1 + e2 + c0 + c1 + c2)):
        raise InvalidInputError(f"{name} needs a finite centre and finite extents >= 0, got {box.center}, {box.extent}")
    return e0 * e1 * e2, thinnest


def _mutual_corners(p: OrientedBox, q: OrientedBox):
    """Each box's corners in the other's frame.

    Returns M (3, 3), q's axes in p's frame; t (3,), q's centre in p's frame;
    half (2, 3), the half extents of p and q; corners (2, 8, 3), q's corners
    in p's frame and p's corners in q's frame.
    """
    M = p.rotation.T @ q.rotation
    t = (q.center - p.center) @ p.rotation
    half = np.array([p.extent, q.extent]) * 0.5
    # p-local x = M y + t for q-local y, so y = M^T (x - t); as row vectors y = x M - t M.
    corners = (_SIGNS * half[::-1, None, :]) @ np.array([M.T, M])
    corners[0] += t
    corners[1] -= t @ M
    return M, t, half, corners


def _clipped_edge_points(M, t, half, corners) -> np.ndarray:
    """(K, 3) points in p's frame (p's centre at 0, p's axes as x, y, z), K <= 48: the ends of
    the parts of q's 12 edges inside p and of p's 12 edges inside q (Liang-Barsky clipping).

    An end is either a box corner (a vertex inside the other box) or where an
    edge crosses one of the other box's faces. Arguments as from _mutual_corners.
    """
    p0 = corners[:, _EDGE_START]  # (2, 12, 3): set 0 = q's edges in p's frame, set 1 = p's edges in q's frame
    d = corners[:, _EDGE_END] - p0
    lim = half[:, None, :] + _TOL  # each set is clipped by the other box's slabs
    # An edge parallel to a slab gets a tiny direction instead of 0: its crossing
    # parameters become +-1e200-ish, i.e. "never leaves the slab" when it starts
    # inside and "never enters" when outside, without a branch.
    crossings = (_LOW_HIGH * lim - p0) / np.where(d == 0.0, 1e-200, d)  # (2 slab sides, 2 sets, 12 edges, 3 axes)
    # ufunc reductions directly: ndarray.min/max add a Python-level wrapper per call.
    lo = np.maximum(np.maximum.reduce(np.minimum.reduce(crossings, 0), -1), 0.0)
    hi = np.minimum(np.minimum.reduce(np.maximum.reduce(crossings, 0), -1), 1.0)
    keep = lo <= hi
    points = p0 + np.array([lo, hi])[..., None] * d  # (2 ends, 2 sets, 12, 3); dropped edges may be far off
    # Back onto the exact box: the slack decides membership but must not add volume
    # (boxes touching face to face would otherwise get a slack-thick sliver).
    h = half[:, None, :]
    points = np.minimum(np.maximum(points, -h), h)
    points[:, 1] = points[:, 1] @ M.T + t
    return points[:, keep].reshape(-1, 3)


def intersection_points(box_a: OrientedBox, box_b: OrientedBox) -> np.ndarray:
    """(K, 3) points in the cloud frame whose convex hull is the intersection of the two boxes.

    They are A's vertices inside B, B's vertices inside A, and the crossings of
    each box's edges with the other's faces (with repeats: a vertex is the end
    of three edges). K = 0 when the boxes are disjoint.
    """
    _check_box(box_a, "box_a")
    _check_box(box_b, "box_b")
    local = _clipped_edge_points(*_mutual_corners(box_a, box_b))
    return box_a.center + local @ box_a.rotation.T


def intersection_volume(box_a: OrientedBox, box_b: OrientedBox) -> float:
    """Volume in m^3 of the intersection of two oriented boxes.

    Exact up to rounding and the 1e-11 m slack of the inside tests. Boxes that
    only touch, and boxes of zero thickness, give 0. Never raises a QhullError:
    a degenerate (flat, linear, single-point) intersection has volume 0.
    """
    vol_a, thin_a = _check_box(box_a, "box_a")
    vol_b, thin_b = _check_box(box_b, "box_b")
    if vol_a <= 0.0 or vol_b <= 0.0:
        return 0.0
    # Work in the frame of the box with the thinnest side, scaled to a unit cube:
    # a flat (plane) box then no longer makes the hull's points needle-thin,
    # which is what puts Qhull's precision at risk.
    if thin_b < thin_a:
        box_a, box_b, vol_a, vol_b = box_b, box_a, vol_b, vol_a
    pose = _mutual_corners(box_a, box_b)
    half, corners = pose[2], pose[3]
    contained = np.logical_and.reduce(np.abs(corners) <= half[:, None, :] + _TOL, (1, 2)).tolist()
    if contained[0] or contained[1]:
        return min(vol_a, vol_b)  # one inside the other (within the slack): no hull needed
    points = _clipped_edge_points(*pose)
    if len(points) < 4:
        return 0.0
    unit = points / box_a.extent
    if np.minimum.reduce(np.maximum.reduce(unit) - np.minimum.reduce(unit)) < 1e-12:
        return 0.0  # flat along one of A's axes, e.g. boxes touching face to face
    try:
        volume = ConvexHull(unit).volume * vol_a
    except (QhullError, ValueError):
        return 0.0  # coplanar or collinear points in a direction not caught above
    return float(min(volume, vol_a, vol_b))


def intersection_ratio(model_box: OrientedBox, scene_box: OrientedBox, min_thickness: float = 0.005) -> float:
    """Share in [0, 1] of the (thickened) model box's volume that the (thickened) scene box covers.

    Both boxes first get every extent raised to at least `min_thickness` metres,
    about their own centres. A plane primitive's box is only as thick as the
    sensor noise across the plane (a millimetre or less; zero for a CAD model's
    face), so without that the intersection of a model plane's box with the
    matching scene plane's box would hinge on sub-millimetre offsets along the
    normal: 0 for any small pose error, and noise otherwise. Thickened to a few
    millimetres (the order of the depth noise and of a good pose's error), the
    ratio measures the in-plane overlap and falls off smoothly with the offset
    along the normal. Boxes thicker than `min_thickness` are unchanged.
    """
    min_thickness = float(min_thickness)
    if not (np.isfinite(min_thickness) and min_thickness >= 0.0):
        raise InvalidInputError(f"min_thickness must be a finite length >= 0 in metres, got {min_thickness}")
    _check_box(model_box, "model_box")
    _check_box(scene_box, "scene_box")
    if min_thickness > 0.0:
        model_box = _thickened(model_box, min_thickness)
        scene_box = _thickened(scene_box, min_thickness)
    volume = model_box.volume
    if volume <= 0.0:
        return 0.0
    return float(min(1.0, intersection_volume(model_box, scene_box) / volume))


def _thickened(box: OrientedBox, min_thickness: float) -> OrientedBox:
    if box.extent.min() >= min_thickness:
        return box
    return OrientedBox(center=box.center, rotation=box.rotation, extent=np.maximum(box.extent, min_thickness))
