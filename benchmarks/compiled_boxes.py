"""PSORR's box verification (psorr.verification.box_score.box_scores) compiled with numba, for
benchmarks/verify_compiled.py.

Not part of the library: it answers one question, whether compiling both verifications would give
PSORR the issue's 50x over ORR per hypothesis. It computes what box_scores computes, hypothesis by
hypothesis in one compiled loop: the model primitives that face the sensor, the scene primitives that
agree with each (kind, orientation, radius), the bounding-sphere and 15-axis separating tests on the
boxes as they are, then the exact volume of the thickened boxes' intersection, and the area-weighted
mean of the best share per primitive.

The exact volume clips each of the 12 faces of the two boxes by the other box's six half-spaces
(Sutherland-Hodgman) and sums the cones from box A's centre over the clipped facets (divergence
theorem). psorr.geometry.box_batch does the same sum with extra care for faces that are (nearly) coplanar,
which this prototype leaves out: there a shared facet would count twice. verify_compiled.py reports the
largest difference from the library's scores (3e-15 over Table 1's 72 runs: no such pair arose).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from psorr.geometry.box_overlap import _TOL  # the library's slack for "inside" and "separated"

_MAXV = 16  # a rectangle clipped by 6 half-spaces has at most 10 vertices
_EYE, _ZERO = np.eye(3), np.zeros(3)  # A's frame, in itself
_RECT_U = np.array([-1.0, 1.0, 1.0, -1.0])  # a face's corners in cyclic order
_RECT_V = np.array([-1.0, -1.0, 1.0, 1.0])


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _mat_vec(R, x, out):
    for r in range(3):
        out[r] = R[r, 0] * x[0] + R[r, 1] * x[1] + R[r, 2] * x[2]


@njit(cache=True)
def _mat_mat(A, B, out, transpose_a):
    """out = A B, or A^T B."""
    for r in range(3):
        for c in range(3):
            if transpose_a:
                out[r, c] = A[0, r] * B[0, c] + A[1, r] * B[1, c] + A[2, r] * B[2, c]
            else:
                out[r, c] = A[r, 0] * B[0, c] + A[r, 1] * B[1, c] + A[r, 2] * B[2, c]


@njit(cache=True)
def _clip(poly, n, out, a, b):
    """Keep the part of polygon poly[:n] (3-D points) where a . x <= b; writes out, returns its size."""
    m = 0
    if n == 0:
        return 0
    prev = poly[n - 1]
    dp = a[0] * prev[0] + a[1] * prev[1] + a[2] * prev[2] - b
    for i in range(n):
        cur = poly[i]
        dc = a[0] * cur[0] + a[1] * cur[1] + a[2] * cur[2] - b
        if (dp <= 0.0) != (dc <= 0.0):  # the edge crosses the plane
            s = dp / (dp - dc)
            for k in range(3):
                out[m, k] = prev[k] + s * (cur[k] - prev[k])
            m += 1
        if dc <= 0.0:
            for k in range(3):
                out[m, k] = cur[k]
            m += 1
        prev, dp = cur, dc
    return m


@njit(cache=True)
def _area(poly, n, normal):
    """Area of the planar polygon poly[:n] with unit normal ``normal``."""
    sx = sy = sz = 0.0
    for i in range(n):
        p, q = poly[i], poly[(i + 1) % n]
        sx += p[1] * q[2] - p[2] * q[1]
        sy += p[2] * q[0] - p[0] * q[2]
        sz += p[0] * q[1] - p[1] * q[0]
    return 0.5 * abs(sx * normal[0] + sy * normal[1] + sz * normal[2])


@njit(cache=True)
def _facets(h_own, axes, centre, h_other, M_other, t_other, buf_a, buf_b, normal, plane_a):
    """Sum over one box's 6 faces of area x (outward normal . face point) after clipping each by the other
    box's slabs; all in A's frame. The box: half extents h_own, axes (columns) ``axes``, centre ``centre``."""
    total = 0.0
    for k in range(3):
        u, v = (k + 1) % 3, (k + 2) % 3
        for side in (-1.0, 1.0):
            for r in range(3):
                normal[r] = side * axes[r, k]
            for c in range(4):
                su, sv = _RECT_U[c], _RECT_V[c]
                for r in range(3):
                    buf_a[c, r] = (centre[r] + side * h_own[k] * axes[r, k] + su * h_own[u] * axes[r, u]
                                   + sv * h_own[v] * axes[r, v])
            n = 4
            src, dst = buf_a, buf_b
            for j in range(3):  # the other box's slab j: |M_j . (x - t)| <= h_j, as two half-spaces
                for sign in (-1.0, 1.0):
                    off = 0.0
                    for r in range(3):
                        plane_a[r] = sign * M_other[r, j]
                        off += plane_a[r] * t_other[r]
                    n = _clip(src, n, dst, plane_a, h_other[j] + off)
                    src, dst = dst, src
                    if n < 3:
                        break
                if n < 3:
                    break
            if n >= 3:
                height = 0.0
                for r in range(3):
                    height += normal[r] * src[0, r]
                total += _area(src, n, normal) * height
    return total


@njit(cache=True)
def _scratch():
    """pair_ratio's working space: two polygon buffers, a face normal and a clipping plane."""
    return np.zeros((3, _MAXV, 3))


@njit(cache=True)
def pair_ratio(ca, Ra, ea, cb, Rb, eb, thickness, scratch):
    """vol(A n B) / vol(A) of two boxes (centres (3,), rotations (3, 3), full extents (3,) m), each
    thickened to at least ``thickness`` m, as psorr.geometry.box_batch.intersection_ratios. ``scratch`` is
    _scratch()'s working space."""
    ha, hb = np.empty(3), np.empty(3)
    for k in range(3):
        ha[k] = max(ea[k], thickness) / 2
        hb[k] = max(eb[k], thickness) / 2
    vol_a, vol_b = 8 * ha[0] * ha[1] * ha[2], 8 * hb[0] * hb[1] * hb[2]
    if vol_a <= 0 or vol_b <= 0:
        return 0.0
    M, t = np.empty((3, 3)), np.empty(3)
    _mat_mat(Ra, Rb, M, True)  # B's axes in A's frame
    for r in range(3):
        t[r] = Ra[0, r] * (cb[0] - ca[0]) + Ra[1, r] * (cb[1] - ca[1]) + Ra[2, r] * (cb[2] - ca[2])
    buf_a, buf_b, normal, plane_a = scratch[0], scratch[1], scratch[2, 0], scratch[2, 1]
    b_in_a, a_in_b = True, True
    for sx in (-1.0, 1.0):
        for sy in (-1.0, 1.0):
            for sz in (-1.0, 1.0):
                for r in range(3):
                    x = t[r] + sx * hb[0] * M[r, 0] + sy * hb[1] * M[r, 1] + sz * hb[2] * M[r, 2]
                    if abs(x) > ha[r] + _TOL:
                        b_in_a = False
                    y = sx * ha[0] * M[0, r] + sy * ha[1] * M[1, r] + sz * ha[2] * M[2, r] - (
                        t[0] * M[0, r] + t[1] * M[1, r] + t[2] * M[2, r])
                    if abs(y) > hb[r] + _TOL:
                        a_in_b = False
    if b_in_a:
        return min(vol_b, vol_a) / vol_a
    if a_in_b:
        return 1.0
    # Cones from A's centre (the frame's origin): 1/3 sum of area x signed height over P's facets.
    volume = (_facets(ha, _EYE, _ZERO, hb, M, t, buf_a, buf_b, normal, plane_a)
              + _facets(hb, M, t, ha, _EYE, _ZERO, buf_a, buf_b, normal, plane_a)) / 3
    volume = min(max(volume, 0.0), min(vol_a, vol_b))
    return volume / vol_a


@njit(cache=True)
def _separated(ca, Ra, ea, cb, Rb, eb, t, R):
    """The bounding-sphere test, then the 15-axis separating test, of two boxes as they are (t (3,) and
    R (3, 3) are scratch)."""
    d0, d1, d2 = cb[0] - ca[0], cb[1] - ca[1], cb[2] - ca[2]
    if 2 * np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) > np.sqrt(_dot(ea, ea)) + np.sqrt(_dot(eb, eb)) + 2 * _TOL:
        return True
    for r in range(3):
        t[r] = Ra[0, r] * d0 + Ra[1, r] * d1 + Ra[2, r] * d2
    _mat_mat(Ra, Rb, R, True)
    for i in range(3):
        if abs(t[i]) > 0.5 * (ea[i] + abs(R[i, 0]) * eb[0] + abs(R[i, 1]) * eb[1] + abs(R[i, 2]) * eb[2]) + _TOL:
            return True
    for j in range(3):
        tb = t[0] * R[0, j] + t[1] * R[1, j] + t[2] * R[2, j]
        if abs(tb) > 0.5 * (ea[0] * abs(R[0, j]) + ea[1] * abs(R[1, j]) + ea[2] * abs(R[2, j]) + eb[j]) + _TOL:
            return True
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            dist = abs(t[i2] * R[i1, j] - t[i1] * R[i2, j])
            ra = ea[i1] * abs(R[i2, j]) + ea[i2] * abs(R[i1, j])
            rb = eb[j1] * abs(R[i, j2]) + eb[j2] * abs(R[i, j1])
            if dist > 0.5 * (ra + rb) + _TOL:
                return True
    return False


@njit(cache=True)
def box_scores(centers, rotations, extents, is_plane, direction, radius, weight, offsets,
               poses, owners, s_centers, s_rotations, s_extents, s_is_plane, s_direction, s_radius,
               thickness, cos_agree, radius_tolerance):
    """(H,) scores of H poses (H, 4, 4), pose h of model owners[h] whose primitives are rows
    offsets[m]:offsets[m + 1] of the library arrays (see psorr.verification.box_score.PrimitiveArrays); the scene's
    primitives are the s_ arrays."""
    H, S = len(poses), len(s_centers)
    scores = np.zeros(H)
    scratch = _scratch()
    R, t = np.empty((3, 3)), np.empty(3)
    c, d, rot = np.empty(3), np.empty(3), np.empty((3, 3))
    tmp_t, tmp_R = np.empty(3), np.empty((3, 3))
    for h in range(H):
        R[:, :], t[:] = poses[h, :3, :3], poses[h, :3, 3]
        m = owners[h]
        total = covered_total = 0.0
        for p in range(offsets[m], offsets[m + 1]):
            _mat_vec(R, centers[p], c)
            c += t
            _mat_vec(R, direction[p], d)
            plane = is_plane[p]
            if plane and _dot(d, c) >= 0:  # a face turned away from the sensor at the origin
                continue
            _mat_mat(R, rotations[p], rot, False)
            best = 0.0
            for s in range(S):
                cos = _dot(d, s_direction[s])
                if plane:
                    if not s_is_plane[s] or cos <= cos_agree:
                        continue
                elif (s_is_plane[s] or abs(radius[p] - s_radius[s]) >= radius_tolerance * radius[p]
                      or abs(cos) <= cos_agree):
                    continue
                if _separated(c, rot, extents[p], s_centers[s], s_rotations[s], s_extents[s], tmp_t, tmp_R):
                    continue
                best = max(best, pair_ratio(c, rot, extents[p], s_centers[s], s_rotations[s], s_extents[s],
                                            thickness, scratch))
            total += weight[p]
            covered_total += best * weight[p]
        scores[h] = covered_total / total if total > 0 else 0.0
    return scores


@njit(cache=True)
def pair_ratios(ca, Ra, ea, cb, Rb, eb, thickness):
    """(N,) pair_ratio of N box pairs (rows of the arrays), as psorr.geometry.box_batch.intersection_ratios."""
    scratch = _scratch()
    out = np.empty(len(ca))
    for i in range(len(ca)):
        out[i] = pair_ratio(ca[i], Ra[i], ea[i], cb[i], Rb[i], eb[i], thickness, scratch)
    return out
