"""Recognition: PSORR over primitive pairs, or the ORR baseline over raw points.

Both methods share the model library, the acceptance stage (point-to-plane
ICP, the point-level check, and suppression of detections that explain the
same pixels) and the stats. They differ in where hypotheses come from and
how each is screened:
- PSORR pairs plane centroids and cylinder axes of the decomposed scene
  (its leftover points decomposed again, finer), clusters the poses by
  vote, and screens each by intersecting model and scene primitive boxes
  (section 2.1.4). Once detections explain some parts, it pairs again among
  the primitives they leave unexplained, then tries single faces and long
  cylinders (psorr.hypotheses.single_plane, psorr.hypotheses.single_cylinder). Points still
  standing on the table unexplained, in part-sized groups, are decomposed again
  at a finer voxel and searched the same way.
- ORR (Papazov and Burschka) pairs random oriented scene points and screens
  every hypothesis with the point-level check.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from scipy.spatial import cKDTree

from psorr.acceptance.ambiguity import NearSymmetryResolver
from psorr.acceptance.claims import PixelClaims, SearchTally
from psorr.acceptance.continuation import on_larger_object
from psorr.acceptance.icp import refine_icp
from psorr.acceptance.unexplained import blanked, on_detected_surface, part_sized, standing_points, standing_unexplained
from psorr.checks import params as check
from psorr.checks.arrays import random_generator
from psorr.checks.clouds import require_seen_from_origin, require_sensor_pose
from psorr.decomposition import decompose
from psorr.decomposition.detail import decompose_leftovers
from psorr.decomposition.support_crop import crop_to_parts, floats_above
from psorr.errors import InvalidInputError, TooSparseError
from psorr.hypotheses.orr import orr_hypotheses
from psorr.hypotheses.pairs import PairCandidates
from psorr.hypotheses.pose_clusters import same_pose, share_out
from psorr.hypotheses.single_cylinder import SingleCylinderMatcher
from psorr.hypotheses.single_plane import SinglePlaneMatcher
from psorr.library.models import ModelLibrary
from psorr.library.ppf import scene_oriented_points
from psorr.recognize_params import METHODS, Recognition, RecognitionStats, RecognizeParams
from psorr.types import Detection, PointCloud, PrimitiveKind
from psorr.verification.point_check import CheckParams, check_pose, check_poses
from psorr.verification.scene_view import SceneView

_COARSE = CheckParams(max_points=300)
_TABLE_EXTENT = 1.2  # in diameters of the largest model: a primitive larger than this is the table


class Recognizer:
    """Find library models in clouds: `Recognizer(library, method="psorr" | "orr").recognize(cloud)`."""

    def __init__(self, library: ModelLibrary, method: str = "psorr", params: RecognizeParams | None = None):
        check.require_instance(library, ModelLibrary, "Recognizer()'s library",
                               "load a saved one with ModelLibrary.load(path), or train one with "
                               "ModelLibrary.from_meshes([mesh paths])")
        if params is not None:
            check.require_instance(params, RecognizeParams, "Recognizer()'s params",
                                   "settings in a dict: RecognizeParams(**settings); None for the defaults")
        if method not in METHODS:
            raise InvalidInputError(f"unknown method {method!r}; choose one of {METHODS}")
        self.library, self.method, self.params = library, method, params or RecognizeParams()
        self.max_diameter = max(m.diameter for m in library.models)
        # Built up front, as model preparation: found on a model's first detection instead, its
        # near-symmetries would add about 0.1 s to that scene.
        self._resolvers = {m.name: NearSymmetryResolver(m) for m in library.models}
        self._model_trees = {m.name: cKDTree(m.points) for m in library.models}
        self._single_plane = SinglePlaneMatcher(library.models, self.params.single_plane)
        self._single_cylinder = SingleCylinderMatcher(library.models, self.params.single_cylinder)
        self._pair_candidates = PairCandidates(library, self.params)

    def recognize(self, cloud: PointCloud, rng: np.random.Generator | None = None) -> Recognition:
        """The library's models found in ``cloud`` (metres, sensor frame, seen from the origin; an image or
        unorganised points). Returns a Recognition: the detections in the order they were accepted (by
        score within each search round), each with model name, ``T_cloud_model`` (4, 4), score in [0, 1]
        and the seen share of the model's surface; and stats (hypotheses, verification ms per hypothesis,
        decomposition and total ms). ``rng`` drives the random draws (default: ``default_rng(0)``), so one
        seed gives the same detections."""
        if not isinstance(cloud, PointCloud):
            raise InvalidInputError(f"recognize() takes a psorr.PointCloud, got {type(cloud).__name__}")
        require_seen_from_origin(cloud, "recognize(): the cloud")
        rng = random_generator(rng, "recognize()")
        start = time.perf_counter()
        if not cloud.valid_mask.any():  # a frame the sensor measured nothing in (the arm over its lens): none here
            return Recognition((), RecognitionStats(self.method, 0, 0.0, 0.0, 0.0, self.library.train_ms))
        view = SceneView(cloud)
        if self.method == "psorr":
            detections, n_hyp, verify_ms, decomposition_ms = self._psorr(cloud, view, rng)
        else:
            candidates, n_hyp, verify_ms = orr_hypotheses(self, cloud, view, rng)
            detections, _ = self._accept(view, candidates)
            decomposition_ms = 0.0
        total = (time.perf_counter() - start) * 1e3
        # No hypothesis, no verification to report: the cost of screening none is no cost per hypothesis.
        stats = RecognitionStats(self.method, n_hyp, verify_ms / n_hyp if n_hyp else 0.0, decomposition_ms, total,
                                 self.library.train_ms)
        return Recognition(tuple(detections), stats)

    def refine(self, cloud: PointCloud, model: str, T_cloud_model: np.ndarray) -> Detection:
        """Judge a known pose of ``model`` in a new view, as recognition judges its candidates: ICP from
        ``T_cloud_model`` (4, 4) onto ``cloud`` (coarse, then fine), its near-symmetric twins told apart
        by render and compare, and the dense point check's score. No search: for a robot that looks
        again at a part it has found, say in its hand and turned so that the features that tell its
        ends apart (``Detection.alternatives``) face the sensor.
        """
        if not isinstance(cloud, PointCloud):
            raise InvalidInputError(f"refine() takes a psorr.PointCloud, got {type(cloud).__name__}")
        require_seen_from_origin(cloud, "refine(): the cloud")
        m = self.library.model(model)
        T = require_sensor_pose(T_cloud_model, "refine()'s T_cloud_model")
        view = SceneView(cloud)
        return self._resolved(view, m, self._fine_icp(view, m, self._coarse_icp(view, m, T)))

    def _coarse_icp(self, view, model, T):
        # 1000 model points and 15 iterations: enough to tell the hopeless candidates (see _accept).
        return refine_icp(view, model.points, model.normals, T, self.params.icp_distance, iterations=15,
                          max_points=1000, skip_holes=True)

    def _coarse_fit(self, view, model, T):
        """The coarse ICP of a candidate, and its coarse point check. A part that slides almost onto
        itself (a channel) is also fitted from where the data place it along its length, and the better
        fit is kept: a slide judged from a tilted start went 2-5 cm the wrong way, from starts the plain
        fit took to within 0.6 mm."""
        starts = [T]
        slid = self._resolvers[model.name].slide_onto_surface(view, T, _COARSE)
        if not np.array_equal(slid, T):
            starts.append(slid)
        fits = [self._coarse_icp(view, model, S) for S in starts]
        checks = [check_pose(view, model.points, model.normals, F, _COARSE) for F in fits]
        best = max(range(len(fits)), key=lambda k: checks[k].score)
        return fits[best], checks[best]

    def _fine_icp(self, view, model, T):
        p = self.params
        return refine_icp(view, model.points, model.normals, T, p.icp_distance / 3, max_points=p.icp_points)

    def _resolved(self, view, model, T) -> Detection:
        """The detection at ``T``, or at the near-symmetric twin the view prefers, with those it left open."""
        T, check, alternatives = self._resolvers[model.name].resolve(view, T, self.params.icp_distance)
        return Detection(model.name, T, check.score, check.visible_fraction, alternatives)

    def _psorr(self, cloud, view, rng):
        p = self.params
        t0 = time.perf_counter()
        # Only what stands on the table is decomposed, with a band of table around it that keeps the
        # table larger than any model, so it still is not paired as a part's face.
        margin = _TABLE_EXTENT / 2 * self.max_diameter
        cropped = crop_to_parts(cloud, view.support_plane, margin, p.support_crop)
        try:
            scene = decompose(cropped, p.decompose, rng)
        except TooSparseError:
            # A handful of points, most of them table, or a few clumps: too few voxels to decompose, and
            # nothing to find (as ORR says).
            return [], 0, 0.0, (time.perf_counter() - t0) * 1e3
        if p.leftover_voxel is not None:
            scene = decompose_leftovers(cropped, scene, p.leftover_voxel, p.decompose, rng)
        tally = SearchTally(decomposition_ms=(time.perf_counter() - t0) * 1e3)
        self._search(cloud, view, scene, tally)
        if p.fine_voxel is not None:
            # What stands on the table and no detection explains gets a second look, decomposed finer.
            standing = standing_points(cropped, view.support_plane, p.support_crop.off_plane)
            rest = standing_unexplained(cropped, standing, tally.detections, self._model_trees, p.icp_distance / 2)
            rest = part_sized(cropped, view.support_plane, rest, _TABLE_EXTENT * self.max_diameter)
            if rest.sum() >= p.min_unexplained:
                t0 = time.perf_counter()
                # The standing points that are explained go; the table stays, for the crop's band.
                left = crop_to_parts(blanked(cropped, standing & ~rest), view.support_plane, margin, p.support_crop)
                try:
                    fine = decompose(left, replace(p.decompose, voxel_size=p.fine_voxel), rng)
                except TooSparseError:
                    fine = None
                tally.decomposition_ms += (time.perf_counter() - t0) * 1e3
                if fine is not None:
                    self._search(cloud, view, fine, tally)
        return tally.detections, tally.hypotheses, tally.verify_ms, tally.decomposition_ms

    def _search(self, cloud, view, scene, tally: SearchTally) -> None:
        """Pair rounds, then single faces, over the primitives of the decomposition ``scene``; what
        they find, and what it cost, is added to ``tally``."""
        p = self.params
        pts, nrm, used = scene_oriented_points(scene.primitives, _TABLE_EXTENT * self.max_diameter)
        prims = [scene.primitives[k] for k in used]
        members = [cloud.points[scene.labels == k] for k in used]
        # Primitives no detection explains yet; those an earlier search's detections explain are out.
        open_ = np.array([not self._on_detected_surface(tally.detections, m) for m in members], dtype=bool)
        for _ in range(p.pair_rounds):
            # In clutter, pairs across other parts fill a model's hypothesis quota; once those parts are
            # explained, their primitives leave the pairing and a part with few votes gets its turn.
            keep = np.flatnonzero(open_)
            candidates, n, ms = self._pair_candidates(pts[keep], nrm[keep], [prims[k] for k in keep])
            more, tally.claims = self._accept(view, candidates, tally.claims)
            tally.add(n, ms)
            open_ &= np.array([not self._on_detected_surface(more, m) for m in members], dtype=bool)
            if not more or open_.sum() < 2:
                break
        # A part showing one face, or one long cylinder, gives no pair; matched by size, it still gives
        # poses. Only primitives no detection explains are tried (a cylinder: nor what the faces' detections
        # explain), so these few poses do not crowd out the pairs'.
        unexplained = np.flatnonzero(open_)
        self._single_search(view, tally, self._single_plane,
                            [prims[k] for k in unexplained if prims[k].kind is PrimitiveKind.PLANE])
        self._single_search(view, tally, self._single_cylinder,
                            [prims[k] for k in unexplained if prims[k].kind is PrimitiveKind.CYLINDER
                             and not self._on_detected_surface(tally.detections, members[k])],
                            beyond=self._single_cylinder)

    def _single_search(self, view, tally: SearchTally, matcher, primitives, beyond=None) -> None:
        """Poses from single ``primitives`` matched by size (``matcher``: a SinglePlaneMatcher or a
        SingleCylinderMatcher), ranked by the coarse point check; the best go through acceptance (poses from
        one cylinder must be seen ``beyond`` it), and what they find, and cost, is added to ``tally``."""
        if not matcher.params.enabled:
            return
        poses, models = matcher.hypotheses(primitives)
        if not len(poses):
            return
        t1 = time.perf_counter()
        # Boxes cannot rank these (one face covers little of a model's boxes); a coarse point check can.
        sp, lib = matcher.params, self.library.models
        checks = check_poses(view, [lib[m].points for m in models], [lib[m].normals for m in models], poses, sp.check)
        scores = np.array([c.score for c in checks])
        order = np.argsort(-scores, kind="stable")
        order = share_out(order[scores[order] >= sp.min_score], models, sp.top)
        # Screening only, like the pairs' box time: neither making the poses nor accepting them.
        ms = (time.perf_counter() - t1) * 1e3
        _, tally.claims = self._accept(view, [(models[k], poses[k]) for k in order], tally.claims, beyond)
        tally.add(len(poses), ms)

    def _on_detected_surface(self, detections, points: np.ndarray, share: float = 0.5) -> bool:
        """Does at least ``share`` of ``points`` (M, 3), a primitive's, lie on the surface of one of ``detections``
        (within half the ICP distance of its model's samples)? The whole surface, not the pixels it covers: a
        part's far side in a full view is explained too, and a part behind a detected one is not."""
        points = points[:: max(1, len(points) // 200)]
        reach = self.params.icp_distance / 2
        return any(on_detected_surface(points, d, self._model_trees, reach).mean() >= share for d in detections)

    def _accept(self, view, candidates, claims: PixelClaims | None = None,
                beyond: SingleCylinderMatcher | None = None) -> tuple[list[Detection], PixelClaims]:
        """The new detections among ``candidates`` (model index, pose), and ``claims`` with them added: the
        detections so far and the pixels they explain. A candidate that shares more than max_shared_pixels of
        its pixels with earlier detections is dropped, unless it scores higher, when it displaces them. Poses
        from one cylinder (``beyond``) must also be supported off the model's long cylinders."""
        p = self.params
        # PSORR's candidates that end up accepted are seen through by at most 0.17 after the coarse
        # pass (22 benchmark scenes), so twice the acceptance bar drops about half the rest. ORR's
        # random-pair poses start rougher: a bushing seen through by half there still converged.
        max_violation = 2 * p.max_violation_ratio if self.method == "psorr" else 1.0
        scored = []
        for model_index, T in candidates:
            model = self.library.models[model_index]
            T, coarse = self._coarse_fit(view, model, T)
            # Most candidates are wrong, and one coarse ICP shows it: too little of the model is measured
            # (of its surface, and of what nearer ones leave in view), or the sensor sees through too much
            # of it. The fine pass is kept for the rest.
            hopeless = (coarse.visible_fraction < p.min_visible_fraction / 2
                        and coarse.unblocked_fraction < p.min_unblocked_fraction / 2)
            if hopeless or coarse.violation_ratio > max_violation:
                continue
            T = self._fine_icp(view, model, T)
            check = check_pose(view, model.points, model.normals, T, p.check)
            seen_enough = (check.visible_fraction >= p.min_visible_fraction
                           or check.unblocked_fraction >= p.min_unblocked_fraction)
            enough_support = (check.n_support >= p.min_support
                              and check.n_support_above_table >= p.min_support_above_table)
            if (enough_support and seen_enough and check.violation_ratio <= p.max_violation_ratio
                    and not floats_above(view.support_plane, model.points[::4], T, p.max_float)
                    and (beyond is None or beyond.seen_beyond(view, model_index, T, p.check, p.max_violation_ratio))):
                scored.append((check.score, model, T, check))
        scored.sort(key=lambda s: -s[0])
        if claims is None:
            claims = PixelClaims(view.n_blocks, p.max_shared_pixels)
        detections, resolved_from = [], []  # the poses resolved here, as found: (model, T)
        for score, model, T, check in scored:
            displaced, detection = claims.rivals(check.supported_blocks, score, 1 - check.violation_ratio), None
            if (displaced is None and self._resolvers[model.name].has_broad_twins
                    and not any(m is model and same_pose(model.points[::50], T, R, 0.05 * model.diameter)
                            for m, R in resolved_from)):
                # A twin pose (an L bracket's legs swapped) that one candidate resolved to kept the pixels from
                # one its near-symmetries take to the true pose: a second chance, at the pose they give. Only
                # for parts whose twins the point check tells apart (a chassis turned end for end scored 0.808
                # to the true 0.800), and not for a copy of a pose already resolved, which resolves alike.
                resolved_from.append((model, T))
                detection = self._resolved(view, model, T)
                check = check_pose(view, model.points, model.normals, detection.T_cloud_model, p.check)
                score = check.score
                displaced = claims.rivals(check.supported_blocks, score, 1 - check.violation_ratio)
            if displaced is None:
                continue
            # Only now, on the few survivors, is a dense check affordable: it tells a part from its
            # near-symmetric twin pose (a tray turned end for end) by the small features.
            if detection is None:
                resolved_from.append((model, T))
                detection = self._resolved(view, model, T)
            if on_larger_object(view, model.points, model.normals, detection.T_cloud_model, p.max_continued,
                                p.continuation):
                continue
            claims.add(detection, check.supported_blocks, score, displaced, 1 - check.violation_ratio)
            detections.append(detection)
        standing = {id(d) for d in claims.detections}  # a later candidate here may have displaced an earlier one
        return [d for d in detections if id(d) in standing], claims

