"""Recognition: PSORR over primitive pairs, PSG over shape-graph cliques, or the ORR baseline over raw points.

A cloud passes the stages in order, each in its own subpackage (docs/pipeline/index.md): the scene as a depth buffer
with its supporting plane (verification); parts at rest tried first, which alone may explain all that stands
(hypotheses.outline, acceptance.by_patch); what stands decomposed into planes, cylinders and their shape graph
(decomposition); pairs or cliques, clustered by vote and screened by intersecting primitive boxes (hypotheses, the
paper's section 2.1.4); ICP, the point check and pixel claims (acceptance); then pairs among the primitives left
unexplained, single faces, long cylinders, the resting poses, a finer second look at what stands unexplained, and the
resting poses over patches an occluder partly hides (hypotheses.hidden_rests). ORR (Papazov's) pairs random points.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from psorr.acceptance.accept import Acceptance
from psorr.acceptance.by_patch import every_patch_found
from psorr.acceptance.by_rank import accept_by_rank
from psorr.acceptance.claims import PixelClaims, SearchResult, SearchTally
from psorr.acceptance.known import known_candidates
from psorr.acceptance.unexplained import DetectedSurfaces
from psorr.checks import params as check
from psorr.checks.arrays import random_generator
from psorr.checks.clouds import require_seen_from_origin, require_sensor_pose
from psorr.decomposition.detail import decompose_with_leftovers
from psorr.decomposition.support_crop import band_rim, crop_to_parts, table_in_band
from psorr.errors import InvalidInputError
from psorr.hypotheses.candidates import CandidateSet
from psorr.hypotheses.hidden_rests import HiddenRests
from psorr.hypotheses.orr import orr_hypotheses
from psorr.hypotheses.outline import OutlineMatcher
from psorr.hypotheses.pairs import PairCandidates
from psorr.hypotheses.pose_clusters import apart_from
from psorr.hypotheses.psg import clique_matcher
from psorr.hypotheses.single_cylinder import SingleCylinderMatcher
from psorr.hypotheses.single_plane import SinglePlaneMatcher
from psorr.library.models import ModelLibrary
from psorr.library.orr_table import OrrTable
from psorr.library.ppf import scene_oriented_points
from psorr.recognize_params import Method, Recognition, RecognitionStats, RecognizeParams
from psorr.segment.per_segment import search_per_segment
from psorr.sensing.noise_context import noise_model
from psorr.sensing.resolution import thin_to_focal
from psorr.types import Detection, PointCloud, PrimitiveKind
from psorr.verification.scene_view import SceneView
from psorr.viz.observer import RecognitionObserver, observed_by
from psorr.viz.observer import observer as current_observer

_NONE_KNOWN = CandidateSet()  # no earlier look's detections to follow
_TABLE_EXTENT = 1.2  # in diameters of the largest model: a primitive larger than this is the table


class Recognizer:
    """Find library models in clouds: ``Recognizer(library, method="psorr" | "psg" | "auto" | "orr").recognize(cloud)``.

    With ``use_colour=True`` the cloud is segmented by colour and distance first (psorr.segment), each
    segment recognised alone, and each detection carries its segment's colour (``Detection.colour``)."""

    def __init__(self, library: ModelLibrary, method: Method | str = Method.PSORR,
                 params: RecognizeParams | None = None, use_colour: bool = False):
        check.require_instance(library, ModelLibrary, "Recognizer()'s library",
                               "load a saved one with ModelLibrary.load(path), or train one with "
                               "ModelLibrary.from_meshes([mesh paths])")
        if params is not None:
            check.require_instance(params, RecognizeParams, "Recognizer()'s params",
                                   "RecognizeParams(acceptance=AcceptParams(...), ...); None for the defaults")
        if method not in tuple(Method):
            raise InvalidInputError(f"unknown method {method!r}; choose one of {[m.value for m in Method]}")
        if not isinstance(use_colour, bool):
            raise InvalidInputError(f"Recognizer()'s use_colour must be True or False, got {use_colour!r}")
        self.library, self.method, self.params = library, Method(method), params or RecognizeParams()
        self.use_colour = use_colour
        # recognize() thins a finer cloud once, on entry; the decompositions of what it thinned need not look again.
        self.scene_decompose = replace(self.params.decompose, thin_finer=False)
        self.max_diameter = max(m.diameter for m in library.models)
        p = self.params
        # Random point pairs start rougher than primitives: PSORR's accepted candidates are seen through by at
        # most 0.08 after the coarse fit (110 fits, the peers' 22 scenes), so PSORR and PSG (cliques of
        # primitives) give up above twice the acceptance bar; from ORR, a bushing seen through by half converged.
        coarse_limit = 1.0 if self.method is Method.ORR else 2 * p.acceptance.max_violation_ratio
        self.acceptance = Acceptance(library, p.acceptance, coarse_limit)
        self.detected = DetectedSurfaces(library.models, p.acceptance.icp_distance / 2, p.support_crop,
                                         _TABLE_EXTENT * self.max_diameter, p.detail.min_unexplained)
        self.pairs = PairCandidates(library, p.pairs)
        self.single_plane = SinglePlaneMatcher(library.models, p.single_plane)
        self.single_cylinder = SingleCylinderMatcher(library.models, p.single_cylinder)
        self.outline = OutlineMatcher(library.models, p.outline, p.acceptance.check,
                                      self.acceptance.clear_as_placed) if p.outline.enabled else None
        self.hidden_rests = None if self.outline is None else HiddenRests(self.outline)  # parts partly hidden
        self.psg = clique_matcher(library, self.method, p.psg)  # PSG's; AUTO's of the large models only
        # ORR's own table of dense model pairs, built (or read from the training cache) once per recognizer.
        self.orr_table = OrrTable.for_library(library, p.orr.table) if self.method is Method.ORR else None

    def recognize(self, cloud: PointCloud, rng: np.random.Generator | None = None,
                  known: Sequence[Detection] = (), observer: RecognitionObserver | None = None) -> Recognition:
        """The library's models found in ``cloud`` (metres, sensor frame, seen from the origin; an image or
        unorganised points). Returns a Recognition: the detections in the order they were accepted (by
        score within each search round), each with model name, ``T_cloud_model`` (4, 4), score in [0, 1]
        and the seen share of the model's surface; and stats (hypotheses, verification ms per hypothesis,
        decomposition and total ms). ``rng`` drives the random draws (default: ``default_rng(0)``), so one
        seed gives the same detections.

        ``known``: detections an earlier look of the same sensor found (PSORR, PSG and AUTO, without colour). Each is
        judged again from its pose, and the search looks only at what they no longer explain
        (:mod:`psorr.acceptance.known`): a cell that looks again after each pick recognises what moved.

        ``observer``: gets every stage as it happens (:class:`psorr.viz.RerunLogger` records them for Rerun)."""
        with observed_by(observer) as watcher, noise_model(self.params.sensor):
            result = self._recognize(cloud, rng, known)
            watcher.detections(result.detections, self.library)
            for stage, ms in (("decomposition", result.stats.decomposition_ms), ("total", result.stats.total_ms)):
                watcher.stage_ms(stage, ms)
        return result

    def _recognize(self, cloud: PointCloud, rng, known: Sequence[Detection]) -> Recognition:
        if not isinstance(cloud, PointCloud):
            raise InvalidInputError(f"recognize() takes a psorr.PointCloud, got {type(cloud).__name__}")
        known = known_candidates(self.library, known)
        if known.candidates and (self.method is Method.ORR or self.use_colour):
            raise InvalidInputError("recognize()'s known detections are followed by the PSORR, PSG and auto methods "
                                    f"without colour; this recognizer is {self.method.value}"
                                    f"{' with colour' if self.use_colour else ''}: pass known=() or use one of them")
        require_seen_from_origin(cloud, "recognize(): the cloud")
        rng = random_generator(rng, "recognize()")
        start = time.perf_counter()
        cloud = self._at_sensor_sampling(cloud)
        current_observer().cloud(cloud)
        if not cloud.valid_mask.any():  # a frame the sensor measured nothing in (the arm over its lens): none here
            return Recognition((), RecognitionStats(self.method, 0, 0.0, 0.0, 0.0, self.library.train_ms))
        found = search_per_segment(self._find, cloud, rng) if self.use_colour else self._find(cloud, rng, known)
        return Recognition(found.detections, RecognitionStats.of(self.method, found, start, self.library.train_ms))

    def _find(self, cloud: PointCloud, rng: np.random.Generator, known: CandidateSet = _NONE_KNOWN) -> SearchResult:
        view = SceneView(cloud)
        current_observer().table(view.support_plane)
        if self.method is Method.ORR:
            return self._orr(view, rng)
        tally = self._new_tally(view)
        self._single_search(view, tally, known)
        return self._decomposed_search(cloud, view, rng, tally)

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
        m, T = self.library.model(model), require_sensor_pose(T_cloud_model, "refine()'s T_cloud_model")
        with noise_model(self.params.sensor):
            return self.acceptance.refine(SceneView(self._at_sensor_sampling(cloud)), m, T)

    def _at_sensor_sampling(self, cloud: PointCloud) -> PointCloud:
        """The cloud thinned to the sampling the thresholds suit, when it is finer (a 3M-point
        structured-light frame); a Kinect-v1-like cloud as it is (docs/decisions/0050)."""
        p = self.params.decompose
        if not (p.sensor_noise and p.thin_finer):
            return cloud
        return thin_to_focal(cloud, p.sensor_focal).cloud

    def _new_tally(self, view: SceneView) -> SearchTally:
        return SearchTally(PixelClaims(view.n_blocks, self.params.acceptance.max_shared_pixels,
                                       self.acceptance.judge(view)))

    def _orr(self, view: SceneView, rng: np.random.Generator) -> SearchResult:
        tally = self._new_tally(view)
        found = orr_hypotheses(self.library, self.orr_table, view, self.params.orr, rng)
        self.acceptance(view, found.candidates, tally.claims)
        tally.add(found.hypotheses, found.verify_ms)
        return tally.result()

    def _decomposed_search(self, cloud: PointCloud, view: SceneView, rng: np.random.Generator,
                           tally: SearchTally) -> SearchResult:
        """PSORR and PSG: parts at rest tried first (:func:`~psorr.acceptance.by_patch.every_patch_found`); when
        they do not explain all that stands, what stands decomposed and searched (_search), parts by their outline,
        what no detection explains decomposed finer and searched again, and parts an occluder partly hides."""
        p = self.params
        followed = bool(tally.detections)  # known parts followed: the search looks only at what they leave
        rests = None
        if self.outline is not None and not followed:  # parts at rest may explain all that stands (decision 0066)
            rests = self.outline.candidates(cloud, view)
            trial = replace(tally, claims=self._new_tally(view).claims)  # the counts so far, claims of its own
            trial.add(rests.hypotheses, rests.verify_ms)
            if every_patch_found(self.acceptance, view, rests, trial.claims) and self.detected.unexplained(
                    cloud, view.support_plane, trial.detections) is None:  # the cloud: what stands is its crop's
                return trial.result()
        t0 = time.perf_counter()
        # Only what stands on the table is decomposed, with a band of table around it that keeps the
        # table larger than any model, so it still is not paired as a part's face.
        margin = _TABLE_EXTENT / 2 * self.max_diameter
        cropped = self._unexplained(crop_to_parts(cloud, view.support_plane, margin, p.support_crop), view, tally,
                                    margin)
        if cropped is None:  # the known parts explain all that stands
            return tally.result()
        tally.decomposition_ms += (time.perf_counter() - t0) * 1e3
        if self.outline is not None and followed:
            rests = self.outline.candidates(cropped, view)
        t0 = time.perf_counter()
        scene = decompose_with_leftovers(cropped, self.scene_decompose, p.detail.leftover_voxel, rng)
        tally.decomposition_ms += (time.perf_counter() - t0) * 1e3
        current_observer().decomposition("scene", cloud, scene)
        if scene is None:  # too sparse to decompose: nothing to find (as ORR says)
            return tally.result()
        self._search(cloud, view, scene, tally)
        if rests is not None:  # parts too small to pair, and pairs' wrong poses, by how parts rest
            self._single_search(view, tally, apart_from(rests, tally.detections, self.library), fine_starts=True)
        if p.detail.fine_voxel is not None:
            self._second_look(cloud, cropped, view, tally, rng)
        if self.hidden_rests is not None:  # parts an arm or a neighbour hides in part (decision 0071)
            found = self.hidden_rests.candidates(cloud, view, lambda pts: self.detected.explain(tally.detections, pts))
            self._single_search(view, tally, found, fine_starts=True)
        return tally.result()

    def _unexplained(self, cropped: PointCloud, view: SceneView, tally: SearchTally,
                     margin: float) -> PointCloud | None:
        """``cropped`` less the standing points the known parts followed so far explain, with its table band
        around what is left (as it is when there are none); None when too few stand unexplained to be a part."""
        if not tally.detections:
            return cropped
        left = self.detected.unexplained(cropped, view.support_plane, tally.detections)
        return None if left is None else crop_to_parts(left, view.support_plane, margin, self.params.support_crop)

    def _second_look(self, cloud, cropped, view, tally: SearchTally, rng) -> None:
        """What stands on the table and no detection explains, decomposed finer and searched again, with a
        narrow band of the table: the table is then the plane at the band's rim, not the one too large to be
        a part's face (docs/decisions/0064-the-second-looks-band.md)."""
        p = self.params
        left = self.detected.unexplained(cropped, view.support_plane, tally.detections)
        if left is None:
            return
        t0 = time.perf_counter()
        # The standing points that are explained are gone; the table stays, for the crop's band.
        left = crop_to_parts(left, view.support_plane, p.detail.fine_band, p.support_crop)
        fine = decompose_with_leftovers(left, replace(self.scene_decompose, voxel_size=p.detail.fine_voxel), None, rng)
        tally.decomposition_ms += (time.perf_counter() - t0) * 1e3
        current_observer().decomposition("detail", cloud, fine)
        if fine is not None:
            rim = band_rim(left, view.support_plane, p.detail.fine_band, p.support_crop)
            self._search(cloud, view, fine, tally, table_in_band(fine.primitives, fine.labels, rim))

    def _search(self, cloud, view, scene, tally: SearchTally, table: int | None = None) -> None:
        """Pair rounds (PSORR), or cliques and then pair rounds (PSG), then single faces and long cylinders,
        over the primitives of the decomposition ``scene`` but the table (its index, or None: the planes too
        large to be a part's face); what they find, and what it cost, is added to ``tally``."""
        pts, nrm, used = scene_oriented_points(scene.primitives, _TABLE_EXTENT * self.max_diameter, table)
        prims = [scene.primitives[k] for k in used]
        members = [cloud.points[scene.labels == k] for k in used]
        # Primitives no detection explains yet; those an earlier search's detections explain are out.
        open_ = np.array([not self.detected.explain(tally.detections, m) for m in members], dtype=bool)
        if self.psg is not None:  # the shape graph's cliques first; what they leave is paired (decision 0069)
            more = self._cliques(cloud, view, scene, tally, table)
            open_ &= np.array([not self.detected.explain(more, m) for m in members], dtype=bool)
        if self.method is not Method.PSG or (self.params.psg.pairs_after and open_.sum() >= 2):
            open_ = self._pair_rounds(view, pts, nrm, prims, members, open_, tally)
        # A part showing one face, or one long cylinder, gives no pair; matched by size, it still gives
        # poses. Only primitives no detection explains are tried (a cylinder: nor what the faces' detections
        # explain), so these few poses do not crowd out the pairs'.
        unexplained = np.flatnonzero(open_)
        faces = [prims[k] for k in unexplained if prims[k].kind is PrimitiveKind.PLANE]
        self._single_search(view, tally, self.single_plane.candidates(view, faces))
        cylinders = [prims[k] for k in unexplained if prims[k].kind is PrimitiveKind.CYLINDER
                     and not self.detected.explain(tally.detections, members[k])]
        self._single_search(view, tally, self.single_cylinder.candidates(view, cylinders), self.single_cylinder)

    def _pair_rounds(self, view, pts, nrm, prims, members, open_, tally: SearchTally) -> np.ndarray:
        """PSORR's pair rounds over the ``open_`` primitives; those still unexplained after them."""
        for _ in range(self.params.pairs.pair_rounds):
            # In clutter, pairs across other parts fill a model's hypothesis quota; once those parts are
            # explained, their primitives leave the pairing and a part with few votes gets its turn.
            keep = np.flatnonzero(open_)
            found = self.pairs(pts[keep], nrm[keep], [prims[k] for k in keep])
            more = self.acceptance(view, found.candidates, tally.claims)
            tally.add(found.hypotheses, found.verify_ms)
            open_ = open_ & np.array([not self.detected.explain(more, m) for m in members], dtype=bool)
            if not more or open_.sum() < 2:
                break
        return open_

    def _cliques(self, cloud, view, scene, tally: SearchTally, table: int | None) -> list:
        """PSG: the scene graph's cliques matched, settled by QPBO and accepted rank by rank
        (:func:`~psorr.acceptance.by_rank.accept_by_rank`); the new detections."""
        found = self.psg.candidates(scene.graph, _TABLE_EXTENT * self.max_diameter, table)
        tally.add(found.found.hypotheses, found.found.verify_ms)
        tally.qpbo_nodes += found.nodes
        tally.qpbo_unlabelled += found.unlabelled
        return accept_by_rank(self.acceptance, self.detected, view, cloud, scene, found, tally.claims)

    def _single_search(self, view, tally: SearchTally, found, beyond=None, fine_starts: bool = False) -> None:
        """The candidates ``found`` from single primitives go through acceptance (poses from one cylinder
        must be seen ``beyond`` it); what they find, and cost, is added to ``tally``."""
        self.acceptance(view, found.candidates, tally.claims, beyond, fine_starts)
        tally.add(found.hypotheses, found.verify_ms)

