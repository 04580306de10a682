"""PSG's candidates accepted one at a time, in the order of the scene surface their poses explain.

A candidate is a clique match, and names the scene primitives it matched. Its rank is QPBO's reward for it:
the box score times the model's surface, the surface of the scene its pose explains, so a large model's
pose on its own faces comes before a small model's pose inside them (docs/decisions/0052-psg-matching.md).
Once a detection of another model explains all of a candidate's primitives, the candidate's correspondences
conflict with that detection's, as two QPBO nodes that give one scene primitive to different models'
primitives do, and it is not fitted. A candidate of the detection's own model is still fitted: a part
turned over onto the same faces (a chassis by 180 degrees) claims them too, and only the fitted scores
tell the two apart.
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
    ``cloud``), accepted into ``claims`` one at a time by rank; those a later one displaced are left out."""
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

    for candidate, vertices in _ranked(found):
        if conflicts(candidate, vertices):
            continue
        more = acceptance(view, [candidate], claims)
        if more:
            detections += more
            explained = {key: True for key, e in explained.items() if e}  # the new ones may explain more
    standing = {id(d) for d in claims.detections}
    return [d for d in detections if id(d) in standing]


def _ranked(found: PsgCandidates) -> list[tuple]:
    """(candidate, its vertices), the most surface explained first (ties in the given order)."""
    ranked = sorted(zip(found.found.candidates, found.vertices, found.explained, strict=True), key=lambda r: -r[2])
    return [(c, v) for c, v, _ in ranked]
