"""Point-level check of poses against a scene's depth buffer (psorr.verification.scene_view.SceneView).

Each model point that would face the sensor under a pose, and is not hidden by the
model itself, is either supported (it lies on the measured surface), a violation (it
lies in front of the measured surface, where the sensor saw through it), occluded
(something nearer hides it, or it lies where the sensor could measure nothing:
SceneView.out_of_sight) or unknown (no measurement there).

Many poses, of one model or several, are checked in one pass (check_poses): their
points are stacked and every step after the pose transform runs once over all of
them. One pose at a time, about 0.25 ms of each check went to numpy's per-call
overhead, as much as 1000 points cost. Each pose's counts are those it gets alone:
only its own points enter them, through the same arithmetic.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from psorr.checks import params as check
from psorr.errors import InvalidInputError
from psorr.sensing.noise_context import depth_noise

# Self-occlusion cells (pose x pixel block) indexed directly up to this many (32 MB of float64); beyond,
# only the cells in use are. A 640x480 buffer has about 19500 blocks: 64 poses take 1.25 million.
_MAX_CELLS = 4_000_000


@dataclass(frozen=True)
class CheckParams:
    """Tolerances of the point check: depth agreement is max(min_tolerance, sigmas x sigma(z)), sigma the
    sensor model's (``RecognizeParams.sensor``, a Kinect v1's by default).
    At most about ``max_points`` of a model's samples are checked (every k-th)."""

    sigmas: float = 3.0
    min_tolerance: float = 0.004
    max_points: int = 1500

    def __post_init__(self):
        # sigmas 0 is one tolerance at every depth; the floor keeps it above 0 then.
        check.non_negative(self, "sigmas")
        check.positive(self, "min_tolerance", unit=" metres")
        check.whole(self, "max_points")


@dataclass(frozen=True)
class PoseCheck:
    """Counts over the model's self-visible sample points, and the verdicts derived from them."""

    n_visible: int
    n_support: int
    n_violation: int
    n_occluded: int
    supported_blocks: np.ndarray  # flat indices of the 4x4-pixel blocks the model explains
    # Supported points higher above the supporting plane than their depth tolerance; all supported points
    # when the view has no supporting plane. The rest the table explains as well as the model does.
    n_support_above_table: int

    @property
    def visible_fraction(self) -> float:
        return self.n_support / self.n_visible if self.n_visible else 0.0

    @property
    def unblocked_fraction(self) -> float:
        """Like visible_fraction, over only the points no nearer surface hides: a part behind others
        is judged by what the sensor could see of it."""
        open_ = self.n_visible - self.n_occluded
        return self.n_support / open_ if open_ > 0 else 0.0

    @property
    def violation_ratio(self) -> float:
        seen = self.n_support + self.n_violation
        return self.n_violation / seen if seen else 1.0

    @property
    def score(self) -> float:
        return float(np.clip(self.visible_fraction * (1.0 - self.violation_ratio), 0.0, 1.0))


def depth_tolerance(z: np.ndarray, params: CheckParams) -> np.ndarray:
    sigma = depth_noise().depth_sigma(z)
    return np.maximum(params.min_tolerance, params.sigmas * sigma)


def _visible(view, points, normals, owner, n_poses):
    """Indices of the stacked posed points (cloud frame) that face the sensor and are not hidden behind
    nearer points of the same pose (``owner`` (N,) names each point's), and their pixels u, v."""
    facing = np.flatnonzero(np.einsum("ij,ij->i", normals, -points) > 0)
    u, v, inside = view.project(points[facing])
    facing, u, v = facing[inside], u[inside], v[inside]
    # Model samples are sparser than pixels, so self-occlusion is judged per block of pixels.
    block = view.block_of(u, v)
    span = int(block.max()) + 1 if len(block) else 1
    cell = owner[facing] * span + block
    size = n_poses * span
    if size > _MAX_CELLS:  # a fine buffer (a dense unorganised cloud): number only the cells in use
        used, cell = np.unique(cell, return_inverse=True)
        size = len(used)
    nearest = np.full(size, np.inf)
    np.minimum.at(nearest, cell, points[facing, 2])
    tol = depth_tolerance(points[facing, 2], CheckParams())
    shown = points[facing, 2] <= nearest[cell] + 2 * tol
    return facing[shown], u[shown], v[shown]


def visible_model_pixels(view, points: np.ndarray, normals: np.ndarray):
    """Indices of posed model points (N, 3) (cloud frame; normals (N, 3)) that face the sensor and are not
    hidden behind nearer points of the same model, and their pixels u, v: three (K,) integer arrays."""
    return _visible(view, points, normals, np.zeros(len(points), dtype=np.int64), 1)


def visible_model_points(view, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Indices of posed model points (cloud frame) that face the sensor and are
    not hidden behind nearer points of the same model."""
    return visible_model_pixels(view, points, normals)[0]


def check_pose(view, model_points, model_normals, T_cloud_model, params=CheckParams()) -> PoseCheck:
    """Classify the model's self-visible points (model frame, (N, 3) m, with unit normals) under the pose
    T_cloud_model (4, 4) (see the module docstring)."""
    return check_poses(view, [model_points], [model_normals], np.asarray(T_cloud_model)[None], params)[0]


def check_poses(view, model_points: Sequence[np.ndarray], model_normals: Sequence[np.ndarray],
                T_cloud_model: np.ndarray, params=CheckParams()) -> list[PoseCheck]:
    """check_pose of P poses T_cloud_model (P, 4, 4), pose k of the model whose samples are
    model_points[k] (N_k, 3) m and model_normals[k] (N_k, 3); sequences of P (one model's arrays may
    repeat). Returns P PoseChecks, each equal to that pose's check_pose."""
    poses = np.asarray(T_cloud_model, dtype=float)
    if poses.ndim != 3 or poses.shape[1:] != (4, 4) or not len(model_points) == len(model_normals) == len(poses):
        raise InvalidInputError(f"check_poses takes poses (P, 4, 4) and P models' points and normals; got poses "
                                f"{poses.shape}, {len(model_points)} point and {len(model_normals)} normal arrays")
    P = len(poses)
    if P == 0:
        return []
    pts, nrm, heights = [], [], []
    plane = view.support_plane
    for T, points, normals in zip(poses, model_points, model_normals):
        stride = max(1, len(points) // params.max_points)
        R, t = T[:3, :3], T[:3, 3]
        pts.append(points[::stride] @ R.T + t)
        nrm.append(normals[::stride] @ R.T)
        if plane is not None:
            heights.append(pts[-1] @ plane[:3] + plane[3])
    n_points = np.array([len(p) for p in pts])
    owner = np.repeat(np.arange(P), n_points)
    pts, nrm = np.concatenate(pts), np.concatenate(nrm)
    visible, u, v = _visible(view, pts, nrm, owner, P)
    who = owner[visible]
    pixel = v * view.width + u
    observed = view.depth[pixel]
    z = pts[visible, 2]
    tol = depth_tolerance(z, params)
    support = np.abs(z - observed) < tol
    # Seen through only where none of the 8 neighbouring pixels measured the surface either: a point on a
    # part's rim falls on the pixel beside it as often as on its own, where the sensor sees the table behind.
    # Counted pixel by pixel, 0.03-0.19 of the points of 40 lone parts at their true poses were seen
    # through, the most on the smallest parts, which have the most rim for their surface.
    violation = np.isfinite(observed) & (z < view.neighbour_depth[pixel] - tol)
    occluded = np.isfinite(observed) & (z > observed + tol)
    # An unmeasured pixel beside a nearer surface is that surface's shadow (a Kinect's projector sits
    # 7.5 cm from its camera): hidden, like what the surface covers. Counted as unknown, a bushing under
    # the arm kept 0.36 of its unhidden points, and was rejected at its true pose.
    occluded |= ~np.isfinite(observed) & (z > view.nearby_depth[pixel] + tol)
    # Where the sensor measured nothing over a region wider than a shadow's edge or a dropout (an arm nearer
    # than its range), something it cannot measure may hide the point: hidden too, not evidence against it.
    occluded |= view.out_of_sight[pixel]
    heights = np.concatenate(heights) if plane is not None else None
    # A thin part lying flat (a circuit board's 1.6 mm) is supported by the table wherever it is posed on
    # it, and at 1.6 m, where the tolerance is 22 mm, so are its components: such support is no evidence.
    above_table = support if plane is None else support & (heights[visible] > tol)

    def count(mask):
        return np.bincount(who[mask], minlength=P)

    n_visible = np.bincount(who, minlength=P)
    n_support, n_violation, n_occluded = count(support), count(violation), count(occluded)
    n_above_table = count(above_table)
    if plane is not None:
        # Model points under the supporting plane are impossible: a pose that sinks a part into the
        # table would otherwise pass on the table's points. Below by more than the pose's tightest
        # tolerance (at least 5 mm), counted in proportion to the share of points judged.
        tightest = np.full(P, np.inf)
        np.minimum.at(tightest, who, tol)
        below = heights < -np.maximum(tightest, 0.005)[owner]
        n_violation += (np.bincount(owner[below], minlength=P) * n_visible / n_points).astype(np.int64)
    # Blocks, not pixels: two poses of one instance check different samples of its points, so
    # only coarse cells tell that they explain the same surface.
    span = view.n_blocks
    cells = np.unique(who[support] * span + view.claim_cell_of(u[support], v[support]))
    ends = np.searchsorted(cells, np.arange(P + 1) * span)
    return [PoseCheck(int(n_visible[k]), int(n_support[k]), int(n_violation[k]), int(n_occluded[k]),
                      cells[ends[k]:ends[k + 1]] - k * span, int(n_above_table[k])) if n_visible[k] else
            PoseCheck(0, 0, 0, 0, np.empty(0, dtype=np.int64), 0) for k in range(P)]
