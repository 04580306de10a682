"""PSG matching (the paper's second recognizer): scene cliques matched to model cliques, the poses
screened by box verification, and conflicting correspondences settled by QPBO.

Each pose hypothesis claims a correspondence for each of its clique's vertices: (scene primitive,
model, model primitive). Every such correspondence is a binary node. Choosing a node earns the best box
score among the hypotheses that claim it; two nodes of one hypothesis earn its score again when chosen
together; two nodes that give one scene primitive to different model primitives may not both be
chosen. What a node earns is the box score times the model's surface: the surface the hypothesis
explains. That last term is not submodular, which is why it takes QPBO. The hypotheses whose nodes QPBO
keeps or cannot decide go on to acceptance, best box score first.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from psorr.checks import params as check
from psorr.hypotheses.candidates import CandidateSet
from psorr.hypotheses.cliques import Clique, CliqueKind, cylinder_match, cylinder_poses, graph_cliques
from psorr.hypotheses.corners import CornerIndex
from psorr.hypotheses.edges import EdgeIndex, EdgeSet
from psorr.hypotheses.pairs import PairParams
from psorr.hypotheses.pose_clusters import densest, share_out
from psorr.hypotheses.primitive_match import RADIUS_TOLERANCE, PrimitiveSizes
from psorr.hypotheses.qpbo import solve_qpbo
from psorr.types import Method, Primitive, PrimitiveKind, PrimitiveShapeGraph
from psorr.verification.box_score import PrimitiveArrays, box_scores

_PAIRS = PairParams()
_CONFLICT = 2.0  # more than any reward a node can earn (box scores are at most 1)


@dataclass(frozen=True)
class PsgParams:
    """``angle_tolerance`` (degrees) between a scene clique's normal-to-normal (or normal-to-axis)
    angles and a model clique's; the radius as in pair matching. The ``max_hypotheses`` poses that most
    scene cliques agree on (PSORR's vote, on a ``same_place`` grid; at least ``least_per_model`` a model)
    are box-scored; those scoring at least ``min_box_score`` (with boxes thickened to ``box_thickness``
    metres) take part in QPBO; of those it keeps, one of each group within ``same_place`` metres (PSORR's
    vote cell) and the angle tolerance, the ``top`` shared out across models, go on to acceptance. With
    ``pairs_after``, the primitives the cliques' detections leave unexplained are paired as PSORR pairs
    them: a part that shows no clique of its model (a board showing its top and one side) is still found
    (docs/decisions/0069). ``method="auto"`` matches the cliques of the models of at least
    ``auto_primitives`` primitives (planes and cylinders), where PSG is the faster method, and pairs every
    model's (docs/decisions/0072)."""

    angle_tolerance: float = 10.0
    pairs_after: bool = True
    auto_primitives: int = 17
    # PSORR's own screening: the same box test, vote cell and number of poses for ICP.
    min_box_score: float = _PAIRS.min_box_score
    box_thickness: float = _PAIRS.box_thickness
    same_place: float = _PAIRS.cluster_cell
    max_hypotheses: int = _PAIRS.max_hypotheses
    least_per_model: int = _PAIRS.least_per_model
    top: int = _PAIRS.refine_top

    def __post_init__(self):
        check.positive(self, "angle_tolerance", "box_thickness", "same_place")
        check.within(self, "min_box_score")
        check.whole(self, "top", "max_hypotheses", "least_per_model", "auto_primitives")
        check.flag(self, "pairs_after")


@dataclass(frozen=True, eq=False)
class PsgCandidates:
    """The candidates for acceptance, and QPBO's nodes: how many, and how many it left unlabelled.
    ``vertices``: per candidate, the scene primitives its clique matched, the table apart; ``explained``: per
    candidate, the scene surface its pose explains (box score times the model's surface, QPBO's reward)."""

    found: CandidateSet
    nodes: int
    unlabelled: int
    vertices: tuple[tuple[int, ...], ...]
    explained: tuple[float, ...]


@dataclass(frozen=True, eq=False)
class _Hypotheses:
    poses: np.ndarray          # (H, 4, 4)
    models: np.ndarray         # (H,)
    nodes: list[tuple]         # per hypothesis, its (scene primitive, model, model primitive) correspondences
    table: int                 # the table's vertex, -1 for none


class PsgMatcher:
    """The library's model cliques, indexed once, matched against a scene's shape graph: every model's, or
    those of the library's models ``indexed`` (their indices in ``library.models``)."""

    def __init__(self, library, params: PsgParams | None = None, indexed: Sequence[int] | None = None):
        self.params = params or PsgParams()
        self.indexed = np.arange(len(library.models)) if indexed is None else np.asarray(indexed, dtype=np.int64)
        self.models = [library.models[k] for k in self.indexed]
        self.model_cliques = [graph_cliques(m.graph) for m in self.models]
        self.corners = CornerIndex(self.models, self.model_cliques)
        self.edges = EdgeIndex(self.models)
        self.sizes = PrimitiveSizes(self.models)
        self.model_primitives = [PrimitiveArrays.of(m.graph.primitives) for m in self.models]
        # Model surface in primitive samples (evenly spaced, so proportional to area).
        self.model_areas = np.array([a.weight.sum() for a in self.model_primitives])
        self.model_centres = np.array([m.points.mean(axis=0) for m in self.models]).reshape(-1, 3)

    def candidates(self, graph: PrimitiveShapeGraph, max_extent: float, table: int | None = None) -> PsgCandidates:
        """Candidates from the cliques of the scene's shape ``graph`` among primitives no longer than
        ``max_extent`` metres, with the table (the vertex ``table``, or when None the largest plane longer than
        that), which is no part's face but the plane a part rests on."""
        found = self._hypotheses(graph, max_extent, table)
        start = time.perf_counter()
        prims = graph.primitives
        # As PSORR's pair votes: the poses most scene cliques agree on, an equal share per model.
        voters = _voters(found.nodes)
        pick = densest(found.poses, found.models, voters, self.model_centres, self.params.same_place,
                       self.params.max_hypotheses, self.params.least_per_model)
        scores = np.zeros(len(found.poses))
        if len(pick):
            scores[pick] = box_scores(self.model_primitives, found.poses[pick], PrimitiveArrays.of(prims),
                                      self.params.box_thickness, found.models[pick])
        good = np.flatnonzero(scores >= max(self.params.min_box_score, 1e-12))
        # A node earns the scene surface its hypothesis explains, not the share of its model: a small
        # model posed inside a large one covers more of itself than the large one, seen in part, does.
        explained = scores * self.model_areas[found.models] if len(found.models) else scores
        kept, n_nodes, n_unlabelled = _settled(good, explained / max(explained.max(initial=0.0), 1e-12),
                                               found.nodes)
        order = kept[np.argsort(-scores[kept], kind="stable")]
        order = share_out(_distinct(order, found.poses, found.models, self.params), found.models, self.params.top)
        verify_ms = (time.perf_counter() - start) * 1e3
        models = self.indexed[found.models]  # the library's indices
        chosen = CandidateSet.chosen(models, found.poses, order, len(found.poses), verify_ms, scores)
        vertices = tuple(tuple(sorted({n[0] for n in found.nodes[k]} - {found.table})) for k in order)
        return PsgCandidates(chosen, n_nodes, n_unlabelled, vertices, tuple(float(explained[k]) for k in order))

    def _hypotheses(self, graph: PrimitiveShapeGraph, max_extent: float, table: int | None) -> _Hypotheses:
        graph, table = _table_turned_over(graph, max_extent, table)
        prims = graph.primitives
        small = {k for k, p in enumerate(prims) if float(np.max(p.box.extent)) <= max_extent and k != table}
        scene_cliques = [c for c in graph_cliques(graph) if set(c.vertices) <= small | {table}]
        fits = self._sizes_fit(prims, table)
        corners = self.corners.match([c for c in scene_cliques if c.kind is CliqueKind.PLANES], prims,
                                     self.params.angle_tolerance, fits)
        edges = self.edges.match(EdgeSet.of(graph, small | {table}), self.params.angle_tolerance, fits)
        poses, models, nodes = [], [], []
        for found in (corners, edges):
            poses += list(found.poses)
            models += found.owners.tolist()
            nodes += [tuple(zip(s.tolist(), [o] * len(s), m.tolist())) for s, o, m in
                      zip(found.scene_vertices, found.owners, found.model_vertices)]
        for scene in (c for c in scene_cliques if c.kind is CliqueKind.PLANE_CYLINDER):
            for index, cliques in enumerate(self.model_cliques):
                for model in cliques:
                    if model.kind is CliqueKind.PLANE_CYLINDER and cylinder_match(
                            scene, model, self.params.angle_tolerance, RADIUS_TOLERANCE):
                        for T in self._poses(scene, model, prims, index):
                            poses.append(T)
                            models.append(index)
                            nodes.append(tuple((s, index, m) for s, m in zip(scene.vertices, model.vertices)))
        return _Hypotheses(np.array(poses).reshape(-1, 4, 4), np.array(models, dtype=np.int64), nodes, table)

    def _sizes_fit(self, prims, table: int):
        """A test of matched cliques (scene vertices (K, v), owners (K,), model vertices (K, v)) -> (K,) bool:
        is each scene face no larger than its model face (psorr.hypotheses.primitive_match)? The table
        stands for the face a part rests on, of any size."""
        compatible = self.sizes.compatible(prims)
        if table >= 0:
            compatible[table] = True

        def fits(scene_vertices, owners, model_vertices):
            rows = self.sizes.offsets[owners][:, None] + model_vertices
            return compatible[scene_vertices, rows].all(axis=1)

        return fits

    def _poses(self, scene: Clique, model: Clique, prims, index: int) -> list[np.ndarray]:
        """The plane-and-cylinder clique's poses whose turned model normal and axis land within the
        tolerance of the scene's."""
        model_prims = [self.models[index].graph.primitives[k] for k in model.vertices]
        scene_prims = [prims[k] for k in scene.vertices]
        cos_tol = np.cos(np.radians(self.params.angle_tolerance))
        out = []
        for T in cylinder_poses(scene_prims, model_prims):
            turned = [T[:3, :3] @ _direction(p) for p in model_prims]
            if all(abs(t @ _direction(s)) >= cos_tol for t, s in zip(turned, scene_prims)):
                out.append(T)
        return out


def clique_matcher(library, method: Method, params: PsgParams) -> PsgMatcher | None:
    """The cliques ``method`` matches: every model's for PSG; for AUTO, those of the models of at least
    ``params.auto_primitives`` primitives (None when there are none, and then AUTO is PSORR); None for the others."""
    if method is Method.PSG:
        return PsgMatcher(library, params)
    if method is not Method.AUTO:
        return None
    large = [k for k, m in enumerate(library.models) if len(m.graph.primitives) >= params.auto_primitives]
    return PsgMatcher(library, params, large) if large else None


def _table_turned_over(graph: PrimitiveShapeGraph, max_extent: float,
                       table: int | None = None) -> tuple[PrimitiveShapeGraph, int]:
    """The graph with its table facing down, and the table's index (-1 for none): the plane ``table``, or when
    None its largest plane longer than ``max_extent``. A part rests on the table by one of its own faces,
    which faces down: the table is that face's plane, so a part showing two faces still makes a corner with it."""
    prims = list(graph.primitives)
    if table is None:
        large = [k for k, p in enumerate(prims) if p.kind is PrimitiveKind.PLANE and np.max(p.box.extent) > max_extent]
        table = max(large, key=lambda k: prims[k].n_points) if large else -1
    if table < 0:
        return graph, -1
    flipped = tuple(-v for v in prims[table].params)
    prims[table] = replace(prims[table], params=flipped)
    return PrimitiveShapeGraph(tuple(prims), graph.edges), table


def _voters(nodes: list[tuple]) -> np.ndarray:
    """(H,) one id per scene clique: the set of scene primitives a hypothesis's nodes name."""
    ids: dict[tuple, int] = {}
    return np.array([ids.setdefault(tuple(sorted({n[0] for n in h})), len(ids)) for h in nodes], dtype=np.int64)


def _distinct(order: np.ndarray, poses: np.ndarray, models: np.ndarray, params: PsgParams) -> list[int]:
    """``order`` without the poses that repeat a better one of the same model (within ``same_place`` metres
    and the angle tolerance): a part's corners all give its pose, and ICP need fit it once."""
    kept: list[int] = []
    cos_tol = np.cos(np.radians(params.angle_tolerance))
    for k in order:
        R, t = poses[k, :3, :3], poses[k, :3, 3]
        if not any(models[j] == models[k] and np.linalg.norm(poses[j, :3, 3] - t) < params.same_place
                   and (np.trace(poses[j, :3, :3].T @ R) - 1) / 2 >= cos_tol for j in kept):
            kept.append(int(k))
    return kept


def _direction(p: Primitive) -> np.ndarray:
    return p.normal if p.kind is PrimitiveKind.PLANE else p.axis


def _settled(good: np.ndarray, scores: np.ndarray, nodes: list[tuple]) -> tuple[np.ndarray, int, int]:
    """The hypotheses among ``good`` that QPBO keeps or leaves undecided, the number of nodes, and how
    many it left unlabelled."""
    if len(good) == 0:
        return good, 0, 0
    index: dict[tuple, int] = {}
    for h in good:
        for node in nodes[h]:
            index.setdefault(node, len(index))
    reward = np.zeros(len(index))
    pairs: dict[tuple[int, int], float] = {}
    for h in good:
        ids = [index[node] for node in nodes[h]]
        for i in ids:
            reward[i] = max(reward[i], scores[h])
        for a in range(len(ids)):
            for b in range(a + 1, len(ids)):
                key = (min(ids[a], ids[b]), max(ids[a], ids[b]))
                pairs[key] = pairs.get(key, 0.0) - scores[h]
    by_scene: dict[int, list[int]] = {}
    for node, i in index.items():
        by_scene.setdefault(node[0], []).append(i)
    for members in by_scene.values():  # one scene primitive, two model primitives: not both
        for a in range(len(members)):
            for b in range(a + 1, len(members)):
                key = (min(members[a], members[b]), max(members[a], members[b]))
                pairs[key] = pairs.get(key, 0.0) + _CONFLICT
    unary = np.column_stack([np.zeros(len(index)), -reward])
    edges = np.array(list(pairs), dtype=np.int64).reshape(-1, 2)
    pairwise = np.column_stack([np.zeros((len(pairs), 3)), np.array(list(pairs.values()))])
    labels = solve_qpbo(unary, edges, pairwise).labels
    kept = [h for h in good if all(labels[index[node]] != 0 for node in nodes[h])]
    return np.array(kept, dtype=np.int64), len(index), int((labels < 0).sum())
