"""Pose hypotheses for parts resting on the table, from the patch of points they raise above it.

A clip, a hinge or a plate lying on the table shows one face or none that the decomposition can
find, and no pair. But a part on a table rests in one of a few stable poses, which leaves three
unknowns: where it lies, and how it is turned about the table's normal. Each connected patch of
points standing above the supporting plane is searched over those three, for every model in each of
its stable resting poses (:func:`psorr.synthetic.resting.stable_rests`): the cost of a pose is
how far the patch's points lie from the model's surface (the model's distance field) plus how far the
model's silhouette reaches past the patch (the patch's distance field), each truncated at the point
check's depth tolerance. A coarse grid of turns and shifts is refined around its best distinct turns,
and the best poses of each patch go through the same ICP and acceptance as every other hypothesis.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import trimesh

from psorr.checks import params as check
from psorr.geometry.distance_field import DistanceField
from psorr.hypotheses.candidates import Candidate, CandidateSet
from psorr.hypotheses.same_surface import SameSurface
from psorr.hypotheses.standing_patches import EXTREME_SHARE, Patch, patch_reach, reaching, standing_grid, table_frame
from psorr.types import PointCloud
from psorr.verification.point_check import CheckParams


@dataclass(frozen=True)
class OutlineParams:
    """Resting-pose hypotheses; distances in metres, areas in m^2, angles in degrees.

    A point stands on the table when it is higher than ``sigmas`` x the sensor's depth sigma at its depth, and
    at least ``min_height``, and no higher than any model rests (the tallest resting shape, plus
    ``height_slack`` and the depth tolerance): higher points are something else's. Patches are drawn on a grid
    of ``cell`` (also the distance fields' cell); a patch of at least ``min_area`` counts when at least
    ``min_standing_share`` of the points in its cells stand (the table's noise lifts specks of at most a fifth;
    a part all, or a third where only its walls clear the noise, as a lid lying open side up). Each model's
    resting poses (its ``rests`` most probable; None: every one) whose height is within
    ``height_slack`` of the patch's top are searched: turns in steps of ``angle_step_deg`` and shifts of the
    centre within ``shift`` in steps of twice the cell, then the ``angles`` best turns at least four steps apart
    are refined in steps of ``fine_angle_step_deg`` and half a cell. A pose's cost is the mean square of the
    distances (truncated at the point check's tolerance, over its square) of the patch's points to the model and
    of the silhouette to the patch, summed; poses costing more than ``max_cost`` are dropped (at 0.5, the points
    lie half a tolerance off on average both ways), and so are those costing more than ``max_cost_ratio`` times
    the patch's cheapest. The ``max_candidates`` best poses of a scene, taken from its patches in turn, go on to
    acceptance. A patch within ``hidden_border`` cells of table that something higher than any rest hides from
    the sensor is searched again, when no part found explains it, as a part partly hidden
    (:mod:`psorr.hypotheses.hidden_rests`); None: never.
    """

    enabled: bool = True
    cell: float = 0.002
    sigmas: float = 2.0
    min_height: float = 0.0027
    min_area: float = 2e-4
    min_standing_share: float = 0.25
    rests: int | None = None
    height_slack: float = 0.006
    angle_step_deg: float = 8.0
    fine_angle_step_deg: float = 2.0
    shift: float = 0.004
    angles: int = 2
    max_cost: float = 0.5
    max_cost_ratio: float = 1.5
    max_candidates: int = 24
    hidden_border: int | None = 4

    def __post_init__(self):
        check.flag(self, "enabled")
        check.positive(self, "cell", "min_height", "min_area", "height_slack", "shift", unit=" metres")
        check.positive(self, "sigmas", "angle_step_deg", "fine_angle_step_deg", "max_cost")
        check.within(self, "max_cost_ratio", low=1.0, high=float("inf"))
        check.within(self, "min_standing_share")
        check.whole(self, "angles", "max_candidates")
        if self.rests is not None:
            check.whole(self, "rests", note=" (None: every stable rest)")
        if self.hidden_border is not None:
            check.whole(self, "hidden_border", note=" (None: no search of partly hidden parts)")


@dataclass(frozen=True, eq=False)
class RestingShape:
    """A model resting one way. T_table_model (4, 4) puts the model's silhouette centroid at x = y = 0
    on the table (z = 0); ``silhouette`` (M, 2) are surface samples seen from above, in that frame;
    ``T_model_table`` is its inverse; ``height`` the rest's height, ``reach`` the silhouette's farthest
    sample from its centroid."""

    model: int
    T_table_model: np.ndarray
    T_model_table: np.ndarray
    silhouette: np.ndarray
    height: float
    reach: float


def _turns(angles: np.ndarray) -> np.ndarray:
    """(A, 3, 3) rotations by ``angles`` (radians) about z."""
    c, s = np.cos(angles), np.sin(angles)
    R = np.zeros((len(angles), 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, -s, s, c, 1.0
    return R


def _placed(angle: float, shift: np.ndarray) -> np.ndarray:
    """(4, 4) the turn by ``angle`` (radians) about z, then the move by ``shift`` (3,)."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = _turns(np.array([angle]))[0], shift
    return T


def _square(centre: np.ndarray, span: np.ndarray) -> np.ndarray:
    """(S, 3) the points ``centre`` (3,) + (a, b, 0) for every a and b in ``span``: shifts on the table."""
    return centre + np.stack(np.meshgrid(span, span, [0.0], indexing="ij"), -1).reshape(-1, 3)


def cheapest(poses: list, ratio: float, clear=None) -> list:
    """``poses`` (cost, ...) costing at most ``ratio`` times the cheapest of those ``clear(poses)`` ((P,) bool;
    None: all) admits, or of all when it admits none, cheapest first: a pose the sensor sees through as placed
    (a finned heat sink's over a gear's patch, its fins standing over the gear's face) sets no bar for the rest."""
    poses = sorted(poses, key=lambda pose: pose[0])
    admitted = [pose for pose, ok in zip(poses, clear(poses) if clear and poses else [True] * len(poses)) if ok]
    return [pose for pose in poses if pose[0] <= ratio * (admitted or poses)[0][0]]


def _subset(points: np.ndarray, count: int) -> np.ndarray:
    """At most ``count`` of ``points``, evenly through them (no draw: the same patch gives the same poses)."""
    return points[np.linspace(0, len(points) - 1, min(count, len(points))).astype(np.int64)]


class OutlineMatcher:
    """The library's models in their resting poses, searched over the patches standing on a scene's table."""

    _SILHOUETTE_SAMPLES = 150  # of the model, seen from above: enough to tell a silhouette from another
    _COARSE_POINTS, _FINE_POINTS = 120, 300  # of the patch

    def __init__(self, models, params: OutlineParams, check: CheckParams | None = None, clear_as_placed=None):
        from psorr.hypotheses.resting_costs import resting_costs  # numba: imported by the search that needs it
        from psorr.synthetic.resting import stable_rests

        self._resting_costs = resting_costs
        self.params, self.check, self.shapes, self.fields = params, check or CheckParams(), [], []
        self.clear_as_placed = clear_as_placed  # (view, model indices, poses (P, 4, 4)) -> (P,) not seen through
        self.truncation = 2 * self.check.min_tolerance  # holds the point check's tolerance out to 2 m and more
        for index, model in enumerate(models):
            self.fields.append(DistanceField.of_points(model.points, params.cell, self.truncation))
            mesh = trimesh.Trimesh(model.vertices, model.faces, process=False)
            for rest in stable_rests(mesh)[:params.rests]:  # [:None]: every one
                T = rest.T_table_model.copy()
                seen = (model.points @ T[:3, :3].T + T[:3, 3])[:, :2]
                T[:2, 3] -= seen.mean(axis=0)
                seen = seen - seen.mean(axis=0)
                self.shapes.append(RestingShape(index, T, np.linalg.inv(T), _subset(seen, self._SILHOUETTE_SAMPLES),
                                                rest.height, float(np.linalg.norm(seen, axis=1).max())))
        self.tallest = max((shape.height for shape in self.shapes), default=0.0) + params.height_slack
        self.widest = max((shape.reach for shape in self.shapes), default=0.0)
        self.same = SameSurface(models)

    def candidates(self, cloud: PointCloud, view) -> CandidateSet:
        """Poses of the resting models over the patches standing on ``view``'s supporting plane in ``cloud``."""
        start = time.perf_counter()
        plane = view.support_plane
        if plane is None or not self.shapes:
            return CandidateSet()
        T, patches = table_frame(plane), self._patches(cloud, plane)
        return self.chosen([self.patch_poses(patch, self.clear_in(view, T)) for patch in patches], T, start)

    def clear_in(self, view, T_cloud_table: np.ndarray):
        """Which of a patch's poses (cost, model, T_table_model) ``view`` does not see through as placed, for
        :func:`cheapest`; None without a test."""
        if self.clear_as_placed is None:
            return None
        return lambda poses: self.clear_as_placed(view, [q[1] for q in poses], [T_cloud_table @ T for *_, T in poses])

    def chosen(self, per_patch: list, T_cloud_table: np.ndarray, start: float) -> CandidateSet:
        """The ``max_candidates`` best of ``per_patch``'s poses (each patch's, cheapest first), in the cloud's
        frame; ``start`` is when their search began (time.perf_counter())."""
        # The patches in turn, each's best first, so that one patch's many near-fits cannot crowd out another's.
        order = sorted(((rank, cost, model, T, k) for k, poses in enumerate(per_patch)
                        for rank, (cost, model, T) in enumerate(poses)), key=lambda pose: pose[:2])
        chosen = order[:self.params.max_candidates]
        return CandidateSet(tuple(Candidate(m, T_cloud_table @ T, region=k) for _, _, m, T, k in chosen),
                            sum(len(p) for p in per_patch), (time.perf_counter() - start) * 1e3, len(per_patch))

    def _patches(self, cloud: PointCloud, plane: np.ndarray):
        """Each connected patch of points standing on the table (see OutlineParams); one wider than any resting
        shape reaches is no one part, and goes on as the pieces the closing of its cells joined, if it has them."""
        grid, p = standing_grid(cloud, plane, self.params, self.tallest, self.check), self.params
        for label in () if grid is None else grid.patches:
            whole = grid.patch(label, grid.labels == label, self.truncation, self.check)
            wide = patch_reach(whole) > self.widest + whole.tolerance + p.shift
            pieces = grid.cores(label, p.min_area) if wide else []
            yield from (grid.patch(label, free, self.truncation, self.check, members) for members, free in pieces)
            if not pieces:
                yield whole

    def patch_poses(self, patch: Patch, clear=None) -> list:
        """(cost, model, T_table_model) of the best poses over ``patch``, cheapest first: those of the resting
        shapes about as high as the patch and no narrower, shifted within ``shift`` (``clear``: :func:`cheapest`'s)."""
        p = self.params
        reach = patch_reach(patch)
        fitting = [shape for shape in self.shapes if reach <= shape.reach + patch.tolerance + p.shift]
        return cheapest(self.poses(patch, fitting, lambda shape: p.shift, 2 * p.cell), p.max_cost_ratio, clear)

    def poses(self, patch: Patch, shapes: list, shift, step: float, within_reach: bool = False) -> list:
        """(cost, model, T_table_model) of the poses over ``patch`` costing at most ``max_cost``: the best
        distinct turns of each of ``shapes`` about as high as the patch, its centre moved within ``shift(shape)``
        metres of the patch's in steps of ``step``, coarsely; the ``max_candidates`` cheapest of those refined.
        ``within_reach``: only the shifts that leave the patch's points within the shape's reach of its centre
        (its silhouette covers the patch), give or take the patch's tolerance and a step."""
        p = self.params
        top = np.percentile(patch.points[:, 2], EXTREME_SHARE)
        centre = np.append(patch.points[:, :2].mean(axis=0), 0.0)
        angles = np.radians(np.arange(0.0, 360.0, p.angle_step_deg))
        points = _subset(patch.points, self._COARSE_POINTS)
        peaks = []
        for shape in shapes:
            if abs(top - shape.height) > p.height_slack + patch.tolerance:
                continue
            shifts = _square(centre, np.arange(-shift(shape), shift(shape) + step / 2, step))
            if within_reach:
                shifts = shifts[reaching(shifts, points, shape.reach + patch.tolerance + step)]
            if not len(shifts):
                continue
            coarse = self._costs(patch, shape, angles, shifts, points)
            for cost, a, k in self._distinct_turns(coarse, angles):
                if step > 2 * p.cell:  # a coarser grid than the refinement reaches across: the ordinary one first
                    cost, shift_k = self._closer(patch, shape, angles[a], shifts[k], step, points)
                    peaks.append((cost, shape, angles[a], shift_k))
                else:
                    peaks.append((cost, shape, angles[a], shifts[k]))
        peaks.sort(key=lambda peak: peak[0])
        # A part's symmetric rests (a rod on any side facet) fit alike: one of each goes on, before and after
        # refinement, so that copies neither crowd out other poses nor cost acceptance a fit each.
        peaks = self.same.distinct([peak for peak in peaks if peak[0] <= p.max_cost], lambda peak: peak[1].model,
                                   lambda peak: _placed(peak[2], peak[3]) @ peak[1].T_table_model, p.max_candidates)
        refined = [self._refined(patch, *peak[1:]) for peak in peaks]
        return self.same.distinct([pose for pose in refined if pose[0] <= p.max_cost], lambda pose: pose[1],
                                  lambda pose: pose[2])

    def _closer(self, patch: Patch, shape: RestingShape, angle: float, shift: np.ndarray, step: float,
                points: np.ndarray) -> tuple[float, np.ndarray]:
        """(cost, shift) of the cheapest of the shifts within half of ``step`` of ``shift`` (3,), in the
        ordinary search's steps of two cells, at turn ``angle``."""
        span = np.arange(-step / 2, step / 2 + self.params.cell / 2, 2 * self.params.cell)
        moves = _square(shift, span)
        costs = self._costs(patch, shape, np.array([angle]), moves, points)[0]
        return float(costs.min()), moves[int(np.argmin(costs))]

    def _distinct_turns(self, costs: np.ndarray, angles: np.ndarray) -> list:
        """(cost, turn index, shift index) of the ``angles`` cheapest cells of ``costs`` (turns x shifts) whose
        turns lie at least four steps apart."""
        apart, out = 4 * np.radians(self.params.angle_step_deg), []
        best = costs.min(axis=1)
        for a in np.argsort(best):
            if all(abs((angles[a] - angles[b] + np.pi) % (2 * np.pi) - np.pi) >= apart for _, b, _ in out):
                out.append((float(best[a]), a, int(np.argmin(costs[a]))))
                if len(out) == self.params.angles:
                    break
        return out

    def _refined(self, patch: Patch, shape: RestingShape, angle: float, shift: np.ndarray) -> tuple:
        """(cost, model, T_table_model) of the cheapest pose within half a coarse step of ``angle`` and a
        cell of ``shift``, in the fine steps."""
        p = self.params
        half = p.angle_step_deg / 2
        turns = angle + np.radians(np.arange(-half, half + 1e-9, p.fine_angle_step_deg))
        span = np.arange(-p.cell, p.cell + p.cell / 4, p.cell / 2)
        moves = _square(shift, span)
        fine = self._costs(patch, shape, turns, moves, _subset(patch.points, self._FINE_POINTS))
        i, j = np.unravel_index(np.argmin(fine), fine.shape)
        return float(fine[i, j]), shape.model, _placed(turns[i], moves[j]) @ shape.T_table_model

    def _costs(self, patch: Patch, shape: RestingShape, angles: np.ndarray, shifts: np.ndarray,
               points: np.ndarray) -> np.ndarray:
        """(A, S) costs of ``shape`` turned by ``angles`` about its centre and moved to ``shifts`` (S, 3):
        the patch's ``points`` (N, 3) off the model's surface, plus the silhouette's samples off the patch,
        each as a mean of squares of distances truncated at the patch's tolerance, over its square."""
        # A model point is T_model_table Rz(-a) (q - s): the turned patch points less the turned shifts.
        model, outside = self.fields[shape.model], patch.outside
        # The standing points of a face near the bar lie above it (Patch.lift): expect them there.
        points = points - np.array([0.0, 0.0, patch.lift(shape.height)])
        return self._resting_costs(shape.T_model_table[:3, :3] @ _turns(-angles), shape.T_model_table[:3, 3],
                                   points, shifts, _turns(angles)[:, :2, :2], shape.silhouette,
                                   model.distances, model.low, model.cell, outside.distances, outside.low,
                                   outside.cell, patch.tolerance)
