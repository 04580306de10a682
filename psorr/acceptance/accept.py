"""Acceptance: screened candidates fitted by ICP, judged by the point check, and settled against the
detections so far by the pixels they explain.

Most candidates are wrong, and one coarse ICP shows it, so the fine fit to the measured depth
(:func:`~psorr.acceptance.projective.refine_projective`) and the dense point check are
kept for the rest (:meth:`Acceptance.fit`). The survivors claim the pixels they explain, best first
(:class:`~psorr.acceptance.claims.PixelClaims`); only the few that win their pixels are told from their
near-symmetric twins by render and compare, and checked for a larger object around them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.acceptance.ambiguity import NearSymmetryResolver
from psorr.acceptance.claims import PixelClaims
from psorr.acceptance.continuation import on_larger_object
from psorr.acceptance.icp import refine_icp
from psorr.acceptance.params import AcceptParams
from psorr.acceptance.render_judge import RenderJudge
from psorr.acceptance.thin_parts import clear_of_table
from psorr.hypotheses.candidates import Candidate
from psorr.hypotheses.pose_clusters import same_pose
from psorr.hypotheses.single_cylinder import SingleCylinderMatcher
from psorr.library.models import Model, ModelLibrary
from psorr.types import Detection
from psorr.verification.point_check import CheckParams, PoseCheck, check_pose, check_poses, depth_tolerance
from psorr.verification.scene_view import SceneView
from psorr.viz.observer import observer

_COARSE = CheckParams(max_points=300)  # the coarse fit's point check: enough to tell the hopeless candidates
_COARSE_ITERATIONS, _COARSE_POINTS = 15, 1000  # the coarse ICP's, as above


@dataclass(frozen=True, eq=False)
class Fitted:
    """A candidate after ICP whose point check passed acceptance's bars: ``model`` at ``T_cloud_model``."""

    model: Model
    T_cloud_model: np.ndarray
    check: PoseCheck


@dataclass(frozen=True, eq=False)
class Claim:
    """A resolved detection, the point check its pixels come from, and the earlier detections it displaces."""

    detection: Detection
    check: PoseCheck
    displaced: list[int]


class Acceptance:
    """Turns candidates into detections for one library. ``coarse_max_violation`` is the seen-through share
    above which a candidate is given up after its coarse fit (candidates of random point pairs start rougher
    than those of primitive pairs)."""

    def __init__(self, library: ModelLibrary, params: AcceptParams, coarse_max_violation: float):
        self.library, self.params, self.coarse_max_violation = library, params, coarse_max_violation
        # Built up front, as model preparation: found on a model's first detection instead, its
        # near-symmetries would add about 0.1 s to that scene.
        self.resolvers = {m.name: NearSymmetryResolver(m) for m in library.models}
        self._spheres = {m.name: (m.points.mean(axis=0), 0.5 * m.diameter) for m in library.models}

    def judge(self, view: SceneView) -> RenderJudge:
        """The render-and-compare judge of conflicting detections in ``view`` (for :class:`PixelClaims`)."""
        return RenderJudge(view, {name: r.renderer for name, r in self.resolvers.items()}, self._spheres)

    def __call__(self, view: SceneView, candidates, claims: PixelClaims,
                 beyond: SingleCylinderMatcher | None = None, fine_starts: bool = False) -> list[Detection]:
        """The new detections among ``candidates`` (:class:`Candidate`), added to ``claims``. A candidate that
        shares more than max_shared_pixels of its pixels with earlier detections is dropped, unless it scores
        higher, when it displaces them. Poses from one cylinder (``beyond``) must also be supported off the
        model's long cylinders. ``fine_starts``: the candidates are placed as finely as the point check's
        tolerance (the resting-pose search's), so those it already finds seen through are given up unfitted."""
        observer().candidates(tuple(candidates), self.library)
        if fine_starts:
            candidates = self._not_seen_through(view, candidates)
        fitted = [f for c in candidates if (f := self.fit(view, c, beyond, fine_starts)) is not None]
        fitted.sort(key=lambda f: -f.check.score)
        return self._settle(view, fitted, claims)

    def _not_seen_through(self, view: SceneView, candidates) -> list[Candidate]:
        """The ``candidates`` whose poses, as placed, the coarse fit's point check does not see through beyond
        its bar. For poses placed within the check's tolerance, the check at the start says what it would
        say after the coarse ICP, in one batched check instead of an ICP each
        (docs/decisions/0049-outline-hypotheses.md)."""
        candidates = list(candidates)
        shares = self.seen_through(view, [c.model for c in candidates], [c.T_cloud_model for c in candidates])
        kept = []
        for c, share in zip(candidates, shares):
            if share > self.coarse_max_violation:
                observer().rejected(self.library.models[c.model].name, c.T_cloud_model,
                                    f"as placed: {share:.0%} of it seen through")
            else:
                kept.append(c)
        return kept

    def seen_through(self, view: SceneView, models: list[int], poses: list[np.ndarray]) -> np.ndarray:
        """(P,) the share of each pose (models[k], the library's indices, at poses[k] (4, 4)) the coarse fit's point
        check sees through, as placed, in one batched check."""
        found = [self.library.models[m] for m in models]
        checks = check_poses(view, [m.points for m in found], [m.normals for m in found],
                             np.array(poses).reshape(-1, 4, 4), _COARSE)
        return np.array([c.violation_ratio for c in checks])

    def clear_as_placed(self, view: SceneView, models: list[int], poses: list[np.ndarray]) -> np.ndarray:
        """(P,) bool: is each pose seen through, as placed, by no more than the coarse fit gives up at?"""
        return self.seen_through(view, models, poses) <= self.coarse_max_violation

    def refine(self, view: SceneView, model: Model, T_cloud_model: np.ndarray) -> Detection:
        """A known pose judged as candidates are: coarse ICP, the fine fit, and its near-symmetric twins told apart."""
        return self._resolved(view, model, self._fine_fit(view, model, self._coarse_icp(view, model, T_cloud_model)))

    def fit(self, view: SceneView, candidate: Candidate, beyond: SingleCylinderMatcher | None = None,
            fine_start: bool = False) -> Fitted | None:
        """The candidate fitted (coarse ICP, then the fine fit) and point-checked, or None when it fails a bar.
        ``fine_start``: the candidate is placed as finely as the point check's tolerance, and the coarse fit
        keeps it as placed when the ICP leaves it hopeless and it was not (docs/decisions/0073)."""
        model = self.library.models[candidate.model]
        T, coarse = self._coarse_fit(view, model, candidate.T_cloud_model, fine_start)
        failed = self._hopeless(coarse)
        if failed is None:
            T = self._fine_fit(view, model, T)
            check = check_pose(view, model.points, model.normals, T, self.params.check)
            failed = self._failed_bar(view, model, T, check)
        if failed is None and beyond is not None and not beyond.seen_beyond(
                view, candidate.model, T, self.params.check, self.params.max_violation_ratio):
            failed = "not seen beyond the cylinder it was found from"
        if failed is not None:
            observer().rejected(model.name, T, failed)
            return None
        return Fitted(model, T, check)

    def _coarse_icp(self, view, model, T):
        return refine_icp(view, model.points, model.normals, T, self.params.icp_distance,
                          iterations=_COARSE_ITERATIONS, max_points=_COARSE_POINTS, skip_holes=True)

    def _coarse_fit(self, view, model, T, keep_start: bool = False) -> tuple[np.ndarray, PoseCheck]:
        """The coarse ICP of a candidate, and its coarse point check. A part that slides almost onto
        itself (a channel) is also fitted from where the data place it along its length, and the better
        fit is kept: a slide judged from a tilted start went 2-5 cm the wrong way, from starts the plain
        fit took to within 0.6 mm. With ``keep_start``, a start the fit leaves hopeless but that is not as
        placed comes back unfitted."""
        starts = [T]
        slid = self.resolvers[model.name].slide_onto_surface(view, T, _COARSE)
        if not np.array_equal(slid, T):
            starts.append(slid)
        fits = [self._coarse_icp(view, model, S) for S in starts]
        checks = [check_pose(view, model.points, model.normals, F, _COARSE) for F in fits]
        best = max(range(len(fits)), key=lambda k: checks[k].score)
        # A start placed within the check's tolerance that the ICP makes hopeless is kept as placed: a part
        # 38% in view beside an arm the sensor could not measure went from 1.1 to 3.5 mm off, 11% seen through.
        if keep_start and self._hopeless(checks[best]) is not None:
            start = check_pose(view, model.points, model.normals, T, _COARSE)
            if self._hopeless(start) is None:
                return T, start
        return fits[best], checks[best]

    def _hopeless(self, coarse: PoseCheck) -> str | None:
        """Why the coarse fit gives the candidate up: too little of the model measured (of its surface, and of
        what nearer ones leave in view), or too much of it seen through; None when it goes on."""
        p = self.params
        if (coarse.visible_fraction < p.min_visible_fraction / 2
                and coarse.unblocked_fraction < p.min_unblocked_fraction / 2):
            return f"coarse fit: {coarse.visible_fraction:.0%} of it seen"
        if coarse.violation_ratio > self.coarse_max_violation:
            return f"coarse fit: {coarse.violation_ratio:.0%} of it seen through"
        return None

    def _fine_fit(self, view, model, T):
        return self.resolvers[model.name].fit_surface(view, T, self.params.icp_distance / 3)

    def _failed_bar(self, view: SceneView, model: Model, T: np.ndarray, check: PoseCheck) -> str | None:
        """The first bar the fitted pose fails, or None when it clears them all: seen enough, supported enough
        (above the table too), not seen through, and resting on the supporting plane rather than floating."""
        p = self.params
        if check.n_support < p.min_support or not clear_of_table(
                view, model, self.resolvers[model.name].renderer, T, check, p.min_support_above_table, p.check):
            return f"{check.n_support} points support it ({check.n_support_above_table} above the table)"
        if check.visible_fraction < p.min_visible_fraction and check.unblocked_fraction < p.min_unblocked_fraction:
            return f"{check.visible_fraction:.0%} of it seen"
        if check.violation_ratio > p.max_violation_ratio:
            return f"{check.violation_ratio:.0%} of it seen through"
        if floats_above(view.support_plane, model.points[::4], T, p.max_float):
            return "floats above the table"
        if sinks_into_table(view, model.points[::4], T, p.check):
            return "sinks into the table"
        return None

    def _resolved(self, view: SceneView, model: Model, T: np.ndarray) -> Detection:
        """The detection at ``T``, or at the near-symmetric twin the view prefers, with those it left open."""
        resolver = self.resolvers[model.name]
        T, check, alternatives = resolver.resolve(view, T, self.params.icp_distance)
        return Detection(model.name, T, check.score, check.visible_fraction, alternatives,
                         unfixed_turn=resolver.unfixed_turn(view, T))

    def _settle(self, view: SceneView, fitted: list[Fitted], claims: PixelClaims) -> list[Detection]:
        """The ``fitted`` (best first) that win their pixels in ``claims`` and sit on no larger object, added
        to it; those a later one displaced here are left out."""
        resolved_from: list[tuple[Model, np.ndarray]] = []  # the poses resolved here, as found
        accepted = []
        for f in fitted:
            claim = self._claim(view, f, claims, resolved_from)
            if claim is None or on_larger_object(view, f.model.points, f.model.normals,
                                                 claim.detection.T_cloud_model, self.params.max_continued,
                                                 self.params.continuation, self.resolvers[f.model.name].renderer):
                observer().rejected(f.model.name, f.T_cloud_model, "its pixels are a better detection's" if claim
                                    is None else "part of a larger object")
                continue
            c = claim.check
            claims.add(claim.detection, c.supported_blocks, c.score, claim.displaced, 1 - c.violation_ratio)
            accepted.append(claim.detection)
        standing = {id(d) for d in claims.detections}
        return [d for d in accepted if id(d) in standing]

    def _claim(self, view: SceneView, f: Fitted, claims: PixelClaims, resolved_from: list) -> Claim | None:
        """The detection ``f`` resolves to, if it wins its pixels: at its own pose, or, when it loses them
        and may be a twin pose (an L bracket's legs swapped), at the pose its near-symmetries take it to.
        Only now, on the few survivors, is a dense check affordable: it tells a part from its near-symmetric
        twin pose (a tray turned end for end) by the small features."""
        c = f.check
        posed = Detection(f.model.name, f.T_cloud_model, c.score)
        displaced = claims.rivals(c.supported_blocks, c.score, 1 - c.violation_ratio, posed)
        if displaced is None and not self._second_chance(f, resolved_from):
            claims.lost_tie(posed, c.score)
            return None
        resolved_from.append((f.model, f.T_cloud_model))
        detection = self._resolved(view, f.model, f.T_cloud_model)
        if displaced is None:
            c = check_pose(view, f.model.points, f.model.normals, detection.T_cloud_model, self.params.check)
            displaced = claims.rivals(c.supported_blocks, c.score, 1 - c.violation_ratio, detection)
            if displaced is None:
                claims.lost_tie(detection, c.score)
                return None
        return Claim(detection, c, displaced)

    def _second_chance(self, f: Fitted, resolved_from: list) -> bool:
        """May a candidate that lost its pixels be a twin pose that one candidate resolved to, keeping the
        pixels from one its near-symmetries take to the true pose? Only for parts whose twins the point check
        tells apart (a chassis turned end for end scored 0.808 to the true 0.800), and not for a copy of a pose
        already resolved, which resolves alike."""
        model = f.model
        return self.resolvers[model.name].has_broad_twins and not any(
            m is model and same_pose(model.points[::50], f.T_cloud_model, R, 0.05 * model.diameter)
            for m, R in resolved_from)


def floats_above(plane: np.ndarray | None, model_points: np.ndarray, T_cloud_model: np.ndarray,
                 max_float: float | None) -> bool:
    """Do ``model_points`` (N, 3), posed by ``T_cloud_model`` (4, 4), all lie more than ``max_float`` metres
    above the supporting ``plane`` (a, b, c, d; the sensor on its positive side)? Parts rest on the table: a
    plate can lie on an arm reaching across the view, within the depth tolerance of its 35 mm radius over
    most of its width, and no check on the measured surface tells it from a real one. False without a plane
    or with max_float None (stacked parts)."""
    if max_float is None or plane is None:
        return False
    lowest = (model_points @ T_cloud_model[:3, :3].T + T_cloud_model[:3, 3]) @ plane[:3] + plane[3]
    return bool(lowest.min() > max_float)


def sinks_into_table(view: SceneView, model_points: np.ndarray, T_cloud_model: np.ndarray, params: CheckParams) -> bool:
    """Does some point of ``model_points`` (N, 3), posed by ``T_cloud_model`` (4, 4), lie deeper below the
    supporting plane than its depth tolerance, where the sensor measured the table in front of it? No
    part can: a pose that fits a small part's faces to a larger one's edge or to noise on the table may
    leave the rest of it inside the table, where the point check counts it hidden, not seen through.
    Where the sensor measured something below the plane instead (a floor beside a box taken for the
    table), the point is not counted. False without a plane."""
    plane = view.support_plane
    if plane is None:
        return False
    points = model_points @ T_cloud_model[:3, :3].T + T_cloud_model[:3, 3]
    tolerance = depth_tolerance(points[:, 2], params)
    sunk = points[points @ plane[:3] + plane[3] < -tolerance]
    if len(sunk) == 0:
        return False
    u, v, inside = view.project(sunk)
    z = view.depth[v * view.width + u]
    measured = view.rays(u, v) * z[:, None]
    with np.errstate(invalid="ignore"):
        on_table = np.abs(measured @ plane[:3] + plane[3]) < depth_tolerance(z, params)
    return bool((inside & np.isfinite(z) & on_table).any())
