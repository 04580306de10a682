"""The gripper against a part's surface samples, compiled: where the pads stop and what they touch, whether
a gripper box holds a sample, and what lies ahead of a seed (:mod:`sim.parts.gripper_fit`).

In numpy every chunk of frames built (frames x samples) float32 arrays of coordinates and masks, then
gathered the few pairs that mattered; that was 12 of the 26 s that synthesising the grasps of four printed
parts took (decision 0054). These walks visit the same pairs without the arrays, in the same float32
arithmetic and the same order, so they give the same stops, areas, contact centroids, hits and spans to the
bit (tests/sim/parts/test_pads_kernel.py); a collision walk stops at a frame's first hit.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def pads_meet(points: np.ndarray, normals: np.ndarray, origins: np.ndarray, closing: np.ndarray,
              offset_u: np.ndarray, offset_v: np.ndarray, half_width: np.float32, half_height: np.float32,
              half_opening: np.float32, tolerance: np.float32, cos_cone: float):
    """For F frames and N samples: ``lo``, ``hi`` (F,) float32 where the pads stop along closing (inf, -inf:
    nothing between them), ``counts`` (F, 2) samples touching at lo and at hi, ``sums`` (F, 2) float64 sums of
    the touching samples' coordinates across closing and up, and ``touching`` (F,) their number.

    Args:
        points: (N, 3) float32 surface samples.
        normals: (N, 3) float32 their outward normals.
        origins: (F, 3) float64 tool points.
        closing: (F, 2) float64 unit closing directions in the table plane.
        offset_u: (F,) float32 each tool point's coordinate along closing.
        offset_v: (F,) float32 each tool point's coordinate across closing.
        half_width: float32 pad half width (m).
        half_height: float32 pad half height (m).
        half_opening: float32 half the largest opening (m).
        tolerance: float32 contact tolerance (m).
        cos_cone: the friction cone's cosine.
    """
    F, N = origins.shape[0], points.shape[0]
    lo = np.full(F, np.inf, np.float32)
    hi = np.full(F, -np.inf, np.float32)
    counts = np.zeros((F, 2), np.int64)
    sums = np.zeros((F, 2), np.float64)
    touching = np.zeros(F, np.int64)
    between = np.empty(N, np.int64)  # the samples between the pads of the frame at hand
    us = np.empty(N, np.float32)
    inf = np.float32(np.inf)
    for f in range(F):
        cu0, cu1 = np.float32(closing[f, 0]), np.float32(closing[f, 1])
        cv0, cv1 = np.float32(closing[f, 1]), np.float32(-closing[f, 0])
        z, ou, ov = np.float32(origins[f, 2]), offset_u[f], offset_v[f]
        low, high, k = inf, -inf, 0
        for s in range(N):
            v = cv0 * points[s, 0] + cv1 * points[s, 1] - ov
            w = points[s, 2] - z
            u = cu0 * points[s, 0] + cu1 * points[s, 1] - ou
            if abs(v) <= half_width and abs(w) <= half_height and abs(u) < half_opening:
                low, high = min(low, u), max(high, u)
                between[k], us[k] = s, u
                k += 1
        lo[f], hi[f] = low, high
        near_lo, near_hi = low + tolerance, high - tolerance
        for j in range(k):
            s, u = between[j], us[j]
            facing = closing[f, 0] * normals[s, 0] + closing[f, 1] * normals[s, 1]
            at_lo = u <= near_lo and facing <= -cos_cone
            at_hi = u >= near_hi and facing >= cos_cone
            if at_lo:
                counts[f, 0] += 1
            if at_hi:
                counts[f, 1] += 1
            if at_lo or at_hi:
                touching[f] += 1
                sums[f, 0] += cv0 * points[s, 0] + cv1 * points[s, 1] - ov
                sums[f, 1] += points[s, 2] - z
    return lo, hi, counts, sums, touching

@njit(cache=True)
def collides(points: np.ndarray, origins: np.ndarray, closing: np.ndarray, offset_u: np.ndarray,
             offset_v: np.ndarray, lo: np.ndarray, hi: np.ndarray, middle: np.ndarray,
             bounds: np.ndarray) -> np.ndarray:
    """(F,) whether a sample lies in a gripper box at each frame, the tool ``middle`` (F,) float32 m along closing
    from the frame's origin, the pads stopping at ``lo`` and ``hi`` (F,) float32 m from it; ``bounds`` (15,)
    float32 are the boxes' limits (:func:`sim.parts.gripper_fit.box_limits` names them). A frame's walk stops at
    its first hit."""
    F, N = origins.shape[0], points.shape[0]
    hit = np.zeros(F, np.bool_)
    (strip_v, strip_w, pad_v, pad_u_lo, pad_u_hi, pad_w_lo, fin_v, fin_u_lo, fin_u_hi, fin_w_lo, palm_v, palm_u,
     palm_w, fin_w_hi, finger_in) = bounds
    for f in range(F):
        cu0, cu1 = np.float32(closing[f, 0]), np.float32(closing[f, 1])
        cv0, cv1 = np.float32(closing[f, 1]), np.float32(-closing[f, 0])
        z, ou, ov, mid = np.float32(origins[f, 2]), offset_u[f], offset_v[f], middle[f]
        beyond_hi, beyond_lo = hi[f] + finger_in, lo[f] - finger_in
        for s in range(N):
            av = abs(cv0 * points[s, 0] + cv1 * points[s, 1] - ov)
            w = points[s, 2] - z
            if not (av <= strip_v and w >= strip_w):
                continue
            u = (cu0 * points[s, 0] + cu1 * points[s, 1] - ou) - mid
            au = abs(u)
            # Descending: each box sweeps everything above its lower end.
            if ((av <= pad_v and au >= pad_u_lo and au <= pad_u_hi and w >= pad_w_lo)
                    or (av <= fin_v and au >= fin_u_lo and au <= fin_u_hi and w >= fin_w_lo)
                    or (av <= palm_v and au <= palm_u and w >= palm_w)
                    # Closing: each finger sweeps in to beside its pad's stop.
                    or (av <= fin_v and w >= fin_w_lo and w <= fin_w_hi and au <= fin_u_hi
                        and (u >= beyond_hi or u <= beyond_lo))):
                hit[f] = True
                break
    return hit


@njit(cache=True)
def ahead(points: np.ndarray, normals: np.ndarray, origins: np.ndarray, closing: np.ndarray, offset_u: np.ndarray,
          offset_v: np.ndarray, tube: np.float32, tolerance: np.float32, lane: np.float32, reach: np.float32,
          cos_cone: float, tube_height: float):
    """``span`` and ``floor`` (F,) float32 of :func:`sim.parts.gripper_fit.ahead` for F seed frames: how far along
    closing the nearest face leaving the part lies in the tube around the ray (inf: none), and the highest
    sample below the seed beside that feature where the fingers go (0: the table). The tube is ``tube`` wide
    (float32, as the coordinates across closing are) and ``tube_height`` high (float64, as heights from a tool
    point are)."""
    F, N = origins.shape[0], points.shape[0]
    span = np.full(F, np.inf, np.float32)
    floor = np.zeros(F, np.float32)
    for f in range(F):
        cu0, cu1 = np.float32(closing[f, 0]), np.float32(closing[f, 1])
        cv0, cv1 = np.float32(closing[f, 1]), np.float32(-closing[f, 0])
        oz, ou, ov = origins[f, 2], offset_u[f], offset_v[f]
        d = span[f]
        for s in range(N):
            v = cv0 * points[s, 0] + cv1 * points[s, 1] - ov
            u = cu0 * points[s, 0] + cu1 * points[s, 1] - ou
            if abs(v) <= tube and abs(points[s, 2] - oz) <= tube_height and u > tolerance \
                    and closing[f, 0] * normals[s, 0] + closing[f, 1] * normals[s, 1] >= cos_cone:
                d = min(d, u)
        span[f] = d
        far, half = d + tolerance, d / np.float32(2)
        for s in range(N):
            z = points[s, 2]
            if not z < oz:
                continue
            v = cv0 * points[s, 0] + cv1 * points[s, 1] - ov
            u = cu0 * points[s, 0] + cu1 * points[s, 1] - ou
            if abs(v) <= lane and (u < -tolerance or u > far) and abs(u - half) <= reach:
                floor[f] = max(floor[f], z)
    return span, floor
