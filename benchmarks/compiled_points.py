"""ORR's point check (psorr.verification.point_check.check_poses) compiled with numba, for
benchmarks/verify_compiled.py.

Not part of the library (see compiled_boxes.py for the question it answers). Pose by pose, in one
compiled loop, it does what check_poses does: every k-th model sample (at most about max_points) is
posed; those facing the sensor and inside the depth buffer are binned in 4x4-pixel blocks to judge
self-occlusion; the self-visible ones are compared with the measured depth (support, violation,
occluded, with the shadow rule); points below the supporting plane add violations. It returns the
counts ORR screens by (PoseCheck's fields but supported_blocks, which ORR's screening does not use).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from psorr.sensing.kinect_noise import KINECT_V1

_SELF_BLOCK = 4  # as psorr.verification.scene_view._SELF_BLOCK
_BASE, _QUAD, _Z0 = KINECT_V1.sigma_base, KINECT_V1.sigma_quad, KINECT_V1.sigma_z0
_STEP = KINECT_V1.disparity_step_px / (525.0 * abs(KINECT_V1.baseline))  # quantisation step / z^2


@njit(cache=True)
def _tolerance(z, sigmas, min_tolerance):
    axial = _BASE + _QUAD * (z - _Z0) ** 2
    step = z * z * _STEP
    return max(min_tolerance, sigmas * np.sqrt(axial * axial + step * step / 12.0))


@njit(cache=True)
def check_poses(depth, nearby, neighbour, width, height, focal, cx, cy, plane, has_plane, points, normals, offsets,
                owners, poses, max_points, sigmas, min_tolerance):
    """(P, 5) int64 counts (visible, support, violation, occluded, support above the table) of P poses
    (P, 4, 4), pose k of the model whose samples are rows offsets[m]:offsets[m + 1] of points, normals
    (N, 3), m = owners[k]; depth, nearby and neighbour (width x height,) are the view's buffers
    (psorr.verification.scene_view.SceneView.depth, .nearby_depth and .neighbour_depth)."""
    P = len(poses)
    out = np.zeros((P, 5), dtype=np.int64)
    bw = width // _SELF_BLOCK + 1
    nearest = np.full(bw * (height // _SELF_BLOCK + 1), np.inf)
    cap = 0
    for m in range(len(offsets) - 1):
        cap = max(cap, offsets[m + 1] - offsets[m])
    px, py, pz, hgt = np.empty(cap), np.empty(cap), np.empty(cap), np.empty(cap)
    pix, blk = np.empty(cap, dtype=np.int64), np.empty(cap, dtype=np.int64)
    for k in range(P):
        m = owners[k]
        start, n_all = offsets[m], offsets[m + 1] - offsets[m]
        stride = max(1, n_all // max_points)
        T = poses[k]
        n, n_points = 0, 0
        for i in range(start, start + n_all, stride):
            p, q = points[i], normals[i]
            x = T[0, 0] * p[0] + T[0, 1] * p[1] + T[0, 2] * p[2] + T[0, 3]
            y = T[1, 0] * p[0] + T[1, 1] * p[1] + T[1, 2] * p[2] + T[1, 3]
            z = T[2, 0] * p[0] + T[2, 1] * p[1] + T[2, 2] * p[2] + T[2, 3]
            hgt[n_points] = plane[0] * x + plane[1] * y + plane[2] * z + plane[3]
            n_points += 1
            nx = T[0, 0] * q[0] + T[0, 1] * q[1] + T[0, 2] * q[2]
            ny = T[1, 0] * q[0] + T[1, 1] * q[1] + T[1, 2] * q[2]
            nz = T[2, 0] * q[0] + T[2, 1] * q[1] + T[2, 2] * q[2]
            if -(nx * x + ny * y + nz * z) <= 0 or z <= 1e-3:
                continue
            u = np.int64(np.round(focal * x / z + cx))
            v = np.int64(np.round(focal * y / z + cy))
            if u < 0 or u >= width or v < 0 or v >= height:
                continue
            px[n], py[n], pz[n] = x, y, z
            pix[n] = v * width + u
            blk[n] = (v // _SELF_BLOCK) * bw + u // _SELF_BLOCK
            nearest[blk[n]] = min(nearest[blk[n]], z)
            n += 1
        n_visible = n_support = n_violation = n_occluded = n_above = 0
        tightest = np.inf
        for j in range(n):
            z = pz[j]
            shown = z <= nearest[blk[j]] + 2 * _tolerance(z, 3.0, 0.004)  # self-occlusion at the default tolerance
            if not shown:
                continue
            n_visible += 1
            tol = _tolerance(z, sigmas, min_tolerance)
            tightest = min(tightest, tol)
            observed = depth[pix[j]]
            if abs(z - observed) < tol:
                n_support += 1
                if not has_plane or (plane[0] * px[j] + plane[1] * py[j] + plane[2] * z + plane[3]) > tol:
                    n_above += 1
            elif np.isfinite(observed):
                if z < neighbour[pix[j]] - tol:  # seen through at the pixel and every neighbour
                    n_violation += 1
                elif z > observed + tol:
                    n_occluded += 1
            elif z > nearby[pix[j]] + tol:
                n_occluded += 1
        for j in range(n):
            nearest[blk[j]] = np.inf
        if has_plane:
            bound = -max(tightest, 0.005)
            below = 0
            for j in range(n_points):
                if hgt[j] < bound:
                    below += 1
            n_violation += np.int64(below * n_visible / n_points)
        out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4] = n_visible, n_support, n_violation, n_occluded, n_above
    return out
