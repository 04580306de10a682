"""PSG's candidates accepted rank by rank: each model's best first, then each model's second, and so on.

A candidate is a clique match, and names the scene primitives it matched. Once a detection of another model
explains all of them, the candidate's correspondences conflict with that detection's, as two QPBO nodes
that give one scene primitive to different models' primitives do, and it is not fitted. A candidate of the
detection's own model is still fitted: a part turned over onto the same faces (a chassis by 180 degrees)
claims them too, and only the fitted scores tell the two apart.
"""

from __future__ import annotations

from psorr.acceptance.accept import Acceptance
from psorr.acceptance.claims import PixelClaims
from psorr.acceptance.unexplained import DetectedSurfaces
from psorr.decomposition.pipeline import Decomposition
from psorr.hypotheses.psg import PsgCandidates
from psorr.types import Detection, PointCloud
from psorr.verification.scene_view import SceneView


def accept_by_rank(acceptance: Acceptance, detected: DetectedSurfaces, view: SceneView, cloud: PointCloud,
                   scene: Decomposition, found: PsgCandidates, claims: PixelClaims) -> list[Detection]:
    """The new detections among ``found`` (the candidates of the cliques of ``scene``, a decomposition of
    ``cloud``), accepted into ``claims`` a rank at a time; those a later rank displaced are left out."""
    names = acceptance.library.names
    explained: dict[tuple[int, str], bool] = {}  # (scene primitive, model): explained by another model's detection
    detections: list[Detection] = []

    def conflicts(candidate, vertices) -> bool:
        model = names[candidate.model]
        others = [d for d in detections if d.model != model]
        if not vertices or not others:
            return False
        for k in vertices:
            if (k, model) not in explained:
                explained[k, model] = detected.explain(others, cloud.points[scene.labels == k])
            if not explained[k, model]:
                return False
        return True

    for turn in _ranks(found.found.candidates, found.vertices):
        more = acceptance(view, [c for c, v in turn if not conflicts(c, v)], claims)
        if more:
            detections += more
            explained = {key: True for key, e in explained.items() if e}  # the new ones may explain more
    standing = {id(d) for d in claims.detections}
    return [d for d in detections if id(d) in standing]


def _ranks(candidates, vertices) -> list[list[tuple]]:
    """(candidate, its vertices) grouped by rank: the k-th group holds each model's k-th candidate, in order."""
    ranks: list[list[tuple]] = []
    seen: dict[int, int] = {}
    for c, v in zip(candidates, vertices, strict=True):
        rank = seen[c.model] = seen.get(c.model, -1) + 1
        if rank == len(ranks):
            ranks.append([])
        ranks[rank].append((c, v))
    return ranks
