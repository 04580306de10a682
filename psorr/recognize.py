"""Recognition: PSORR over primitive pairs, or the ORR baseline over raw points.

Both methods share the model library, the acceptance stage (point-to-plane
ICP, the point-level check, and suppression of detections that explain the
same pixels) and the stats. They differ in where hypotheses come from and
how each is screened:
- PSORR pairs plane centroids and cylinder axes of the decomposed scene
  (its leftover points decomposed again, finer), clusters the poses by
  vote, and screens each by intersecting model and scene primitive boxes
  (section 2.1.4). Once detections explain some parts, it pairs again among
  the primitives they leave unexplained, then tries single faces.
- ORR (Papazov and Burschka) pairs random oriented scene points and screens
  every hypothesis with the point-level check.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from psorr.ambiguity import NearSymmetryResolver
from psorr.box_score import PrimitiveArrays, box_scores
from psorr.decomposition import DecomposeParams, decompose
from psorr.decomposition.detail import decompose_leftovers
from psorr.errors import InvalidInputError
from psorr.library import ModelLibrary
from psorr.orr import orr_hypotheses
from psorr.pose_clusters import densest_poses
from psorr.primitive_match import PrimitiveSizes
from psorr.single_plane import SinglePlaneMatcher, SinglePlaneParams
from psorr.support_crop import SupportCropParams, crop_to_parts
from psorr.types import Detection, PointCloud, PrimitiveKind
from psorr.verify import CheckParams, SceneView, check_pose, refine_icp

METHODS = ("psorr", "orr")


@dataclass(frozen=True)
class RecognizeParams:
    """Settings of recognition; distances in metres."""

    decompose: DecomposeParams = field(default_factory=lambda: DecomposeParams(voxel_size=0.008))
    leftover_voxel: float | None = 0.005  # PSORR: points the decomposition left unlabelled, again at this voxel
    max_hypotheses: int = 100           # PSORR: clustered hypotheses screened by boxes, per round
    cluster_cell: float = 0.02          # PSORR: position grid of the vote clustering
    min_box_score: float = 0.1
    box_thickness: float = 0.04         # boxes are thickened to this: pair poses are off by a centimetre or so
    refine_top: int = 24                # best screened hypotheses that get ICP and the point check
    pair_rounds: int = 2                # PSORR: pairing again among the primitives detections leave unexplained
    orr_hypotheses: int = 1500          # ORR: hypotheses drawn and checked point by point
    icp_distance: float = 0.012
    check: CheckParams = field(default_factory=CheckParams)
    min_visible_fraction: float = 0.35
    min_unblocked_fraction: float = 0.6  # or, for a part partly hidden by others, of its unhidden points
    max_violation_ratio: float = 0.15
    min_support: int = 60
    max_shared_pixels: float = 0.3      # a detection sharing more of its pixels with a better one is dropped
    single_plane: SinglePlaneParams = field(default_factory=SinglePlaneParams)  # PSORR: poses from one face
    support_crop: SupportCropParams = field(default_factory=SupportCropParams)  # PSORR: what is decomposed

    def __post_init__(self):
        for name in ("max_hypotheses", "refine_top", "pair_rounds", "orr_hypotheses", "min_support"):
            if int(getattr(self, name)) < 1:
                raise InvalidInputError(f"RecognizeParams.{name} must be >= 1, got {getattr(self, name)}")
        if self.leftover_voxel is not None and not self.leftover_voxel > 0:
            raise InvalidInputError(f"RecognizeParams.leftover_voxel must be > 0 metres or None, "
                                    f"got {self.leftover_voxel}")
        for name in ("cluster_cell", "box_thickness", "icp_distance"):
            if not getattr(self, name) > 0:
                raise InvalidInputError(f"RecognizeParams.{name} must be > 0 metres, got {getattr(self, name)}")
        for name in ("min_box_score", "min_visible_fraction", "min_unblocked_fraction", "max_violation_ratio", "max_shared_pixels"):
            if not 0 <= getattr(self, name) <= 1:
                raise InvalidInputError(f"RecognizeParams.{name} must lie in [0, 1], got {getattr(self, name)}")


@dataclass(frozen=True)
class RecognitionStats:
    method: str
    hypotheses: int
    verify_ms_per_hypothesis: float
    decomposition_ms: float
    total_ms: float
    train_ms: float


@dataclass(frozen=True)
class Recognition:
    detections: tuple[Detection, ...]
    stats: RecognitionStats


def _scene_oriented_points(primitives, max_extent):
    """Plane centroids with normals and cylinder axes (the point nearest the centroid) of
    object-sized primitives; a primitive larger than every model (the table) is skipped."""
    pts, nrm, used = [], [], []
    for index, p in enumerate(primitives):
        if max(p.box.extent) > max_extent:
            continue
        if p.kind is PrimitiveKind.PLANE:
            pts.append(p.centroid)
            nrm.append(p.normal)
        else:
            pts.append(p.axis_point + ((p.centroid - p.axis_point) @ p.axis) * p.axis)
            nrm.append(p.axis)
        used.append(index)
    return np.array(pts).reshape(-1, 3), np.array(nrm).reshape(-1, 3), used


_COARSE = CheckParams(max_points=300)
_TABLE_EXTENT = 1.2  # in diameters of the largest model: a primitive larger than this is the table


def _share_out(order, models, limit):
    """Up to `limit` of the ranked hypotheses, taken round-robin across models
    so that one model's many near-duplicates cannot fill every slot."""
    queues = {}
    for k in order:
        queues.setdefault(int(models[k]), []).append(k)
    chosen = []
    while len(chosen) < limit and any(queues.values()):
        for queue in queues.values():
            if queue and len(chosen) < limit:
                chosen.append(queue.pop(0))
    return chosen


class Recognizer:
    """Find library models in clouds: `Recognizer(library, method="psorr" | "orr").recognize(cloud)`."""

    def __init__(self, library: ModelLibrary, method: str = "psorr", params: RecognizeParams | None = None):
        if method not in METHODS:
            raise InvalidInputError(f"unknown method {method!r}; choose one of {METHODS}")
        self.library, self.method, self.params = library, method, params or RecognizeParams()
        self.max_diameter = max(m.diameter for m in library.models)
        self._sizes = PrimitiveSizes(library.models)
        self.model_centres = np.array([m.points.mean(axis=0) for m in library.models])  # (M, 3), model frames
        # Built up front, as model preparation: found on a model's first detection instead, its
        # near-symmetries would add about 0.1 s to that scene.
        self._resolvers = {m.name: NearSymmetryResolver(m) for m in library.models}
        self._model_trees = {m.name: cKDTree(m.points) for m in library.models}
        self._single_plane = SinglePlaneMatcher(library.models, self.params.single_plane)
        self._model_prims = [PrimitiveArrays.of(m.graph.primitives) for m in library.models]

    def recognize(self, cloud: PointCloud, rng: np.random.Generator | None = None) -> Recognition:
        if not isinstance(cloud, PointCloud):
            raise InvalidInputError(f"recognize() takes a psorr.PointCloud, got {type(cloud).__name__}")
        rng = rng if rng is not None else np.random.default_rng(0)
        start = time.perf_counter()
        view = SceneView(cloud)
        if self.method == "psorr":
            detections, n_hyp, verify_ms, decomposition_ms = self._psorr(cloud, view, rng)
        else:
            candidates, n_hyp, verify_ms = orr_hypotheses(self, cloud, view, rng)
            detections, _ = self._accept(view, candidates)
            decomposition_ms = 0.0
        total = (time.perf_counter() - start) * 1e3
        stats = RecognitionStats(self.method, n_hyp, verify_ms / max(n_hyp, 1), decomposition_ms, total,
                                 self.library.train_ms)
        return Recognition(tuple(detections), stats)

    def _psorr(self, cloud, view, rng):
        p = self.params
        t0 = time.perf_counter()
        # Only what stands on the table is decomposed, with a band of table around it that keeps the
        # table larger than any model, so it still is not paired as a part's face.
        cropped = crop_to_parts(cloud, view.support_plane, _TABLE_EXTENT / 2 * self.max_diameter, p.support_crop)
        scene = decompose(cropped, p.decompose, rng)
        if p.leftover_voxel is not None:
            scene = decompose_leftovers(cropped, scene, p.leftover_voxel, p.decompose, rng)
        decomposition_ms = (time.perf_counter() - t0) * 1e3
        pts, nrm, used = _scene_oriented_points(scene.primitives, _TABLE_EXTENT * self.max_diameter)
        prims = [scene.primitives[k] for k in used]
        members = [cloud.points[scene.labels == k] for k in used]
        detections, claimed, n_hyp, verify_ms = [], None, 0, 0.0
        open_ = np.ones(len(used), dtype=bool)  # primitives no detection explains yet
        for _ in range(p.pair_rounds):
            # In clutter, pairs across other parts fill a model's hypothesis quota; once those parts are
            # explained, their primitives leave the pairing and a part with few votes gets its turn.
            keep = np.flatnonzero(open_)
            candidates, n, ms = self._pair_candidates(pts[keep], nrm[keep], [prims[k] for k in keep])
            more, claimed = self._accept(view, candidates, claimed)
            detections, n_hyp, verify_ms = detections + more, n_hyp + n, verify_ms + ms
            open_ &= [not self._on_detected_surface(more, m) for m in members]
            if not more or open_.sum() < 2:
                break
        if p.single_plane.enabled:
            # A part showing one face gives no pair; its face, matched by size, still gives a pose.
            # Only faces no detection explains are tried, so these few poses do not crowd out the pairs'.
            t1 = time.perf_counter()
            faces = [prims[k] for k in np.flatnonzero(open_) if prims[k].kind is PrimitiveKind.PLANE]
            face_poses, face_models = self._single_plane.hypotheses(faces)
            face_candidates = self._best_face_poses(view, face_poses, face_models)
            n_hyp, verify_ms = n_hyp + len(face_poses), verify_ms + (time.perf_counter() - t1) * 1e3
            more, claimed = self._accept(view, face_candidates, claimed)
            detections += more
        return detections, n_hyp, verify_ms, decomposition_ms

    def _on_detected_surface(self, detections, points: np.ndarray, share: float = 0.5) -> bool:
        """Does at least ``share`` of ``points`` (M, 3), a primitive's, lie on the surface of one of ``detections``
        (within half the ICP distance of its model's samples)? The whole surface, not the pixels it covers: a
        part's far side in a full view is explained too, and a part behind a detected one is not."""
        points = points[:: max(1, len(points) // 200)]
        for d in detections:
            T_model_cloud = np.linalg.inv(d.T_cloud_model)
            local = points @ T_model_cloud[:3, :3].T + T_model_cloud[:3, 3]
            gap, _ = self._model_trees[d.model].query(local, distance_upper_bound=self.params.icp_distance / 2)
            if np.isfinite(gap).mean() >= share:
                return True
        return False

    def _pair_candidates(self, pts, nrm, scene_prims):
        """Pose hypotheses from pairs of the scene's oriented points (K, 3) and their primitives: matched
        in the hash table, clustered by vote, and the best by box score. Returns the (model index, pose)
        candidates, the number of clustered hypotheses, and the ms spent verifying them."""
        p = self.params
        poses, models = np.empty((0, 4, 4)), np.empty(0, dtype=np.int64)
        if len(pts) >= 2:  # pairs need two oriented points
            i, j = np.nonzero(np.linalg.norm(pts[:, None] - pts[None], axis=2) <= self.max_diameter)
            keep = i != j
            i, j = i[keep], j[keep]
            scene_index, rows = self.library.table.lookup(pts[i], nrm[i], pts[j], nrm[j])
            scene_index, rows = self._plausible(scene_prims, i, j, scene_index, rows)
            if len(rows):
                poses, models = self.library.table.poses(scene_index, rows, pts[i], nrm[i], pts[j])
                poses, models = densest_poses(poses, models, scene_index, self.model_centres, p.cluster_cell,
                                              p.max_hypotheses)
        t1 = time.perf_counter()
        scores, scene = np.zeros(len(poses)), PrimitiveArrays.of(scene_prims)
        for m in np.unique(models):
            mine = models == m
            scores[mine] = box_scores(self._model_prims[m], poses[mine], scene, p.box_thickness)
        order = np.argsort(-scores, kind="stable")
        order = _share_out(order[scores[order] >= p.min_box_score], models, p.refine_top)
        verify_ms = (time.perf_counter() - t1) * 1e3
        return [(models[k], poses[k]) for k in order], len(poses), verify_ms

    def _plausible(self, scene_prims, i, j, scene_index, rows):
        """The lookup matches whose scene primitives could be parts of their model primitives (kind, size)."""
        table, sizes = self.library.table, self._sizes
        fits = sizes.compatible(scene_prims)
        a, b = table.first[rows], table.second[rows]
        owner = sizes.offsets[table.model[a]]
        keep = fits[i[scene_index], owner + table.primitive[a]] & fits[j[scene_index], owner + table.primitive[b]]
        return scene_index[keep], rows[keep]

    def _best_face_poses(self, view, poses, models) -> list[tuple[int, np.ndarray]]:
        # Boxes cannot rank these (one face covers little of a model's boxes); a coarse point check can.
        sp = self.params.single_plane
        scores = np.array([check_pose(view, self.library.models[m].points, self.library.models[m].normals, T,
                                      sp.check).score for T, m in zip(poses, models)])
        order = np.argsort(-scores, kind="stable")
        order = _share_out(order[scores[order] >= sp.min_score], models, sp.top)
        return [(models[k], poses[k]) for k in order]

    def _accept(self, view, candidates, claimed: np.ndarray | None = None) -> tuple[list[Detection], np.ndarray]:
        """Detections among ``candidates`` (model index, pose), and the 4x4-pixel blocks claimed so far
        (``claimed``: by earlier detections, which a new one may share only up to max_shared_pixels)."""
        p = self.params
        # PSORR's candidates that end up accepted are seen through by at most 0.17 after the coarse
        # pass (22 benchmark scenes), so twice the acceptance bar drops about half the rest. ORR's
        # random-pair poses start rougher: a bushing seen through by half there still converged.
        max_violation = 2 * p.max_violation_ratio if self.method == "psorr" else 1.0
        scored = []
        for model_index, T in candidates:
            model = self.library.models[model_index]
            # Coarse: 1000 model points and 15 iterations, enough to tell the hopeless candidates (below).
            T = refine_icp(view, model.points, model.normals, T, p.icp_distance, iterations=15, max_points=1000)
            # Most candidates are wrong, and one coarse ICP shows it: too little of the model is measured,
            # or the sensor sees through too much of it. The fine pass is kept for the rest.
            coarse = check_pose(view, model.points, model.normals, T, _COARSE)
            if coarse.visible_fraction < p.min_visible_fraction / 2 or coarse.violation_ratio > max_violation:
                continue
            T = refine_icp(view, model.points, model.normals, T, p.icp_distance / 3)
            check = check_pose(view, model.points, model.normals, T, p.check)
            seen_enough = (check.visible_fraction >= p.min_visible_fraction
                           or check.unblocked_fraction >= p.min_unblocked_fraction)
            if check.n_support >= p.min_support and seen_enough and check.violation_ratio <= p.max_violation_ratio:
                scored.append((check.score, model, T, check))
        scored.sort(key=lambda s: -s[0])
        if claimed is None:
            claimed = np.zeros(view.n_blocks, dtype=bool)
        detections = []
        for _, model, T, check in scored:
            blocks = check.supported_blocks
            if claimed[blocks].mean() > p.max_shared_pixels:
                continue
            claimed[blocks] = True
            # Only now, on the few survivors, is a dense check affordable: it tells a part from its
            # near-symmetric twin pose (a tray turned end for end) by the small features.
            T, check = self._resolvers[model.name].resolve(view, T, p.icp_distance)
            detections.append(Detection(model.name, T, check.score, check.visible_fraction))
        return detections, claimed

