"""PSG's acceptance by rank (psorr.acceptance.by_rank): one candidate at a time, the most scene surface
explained first, with acceptance and the explained surfaces stood in for."""

from types import SimpleNamespace

import numpy as np

from psorr.acceptance.by_rank import accept_by_rank
from psorr.hypotheses.candidates import Candidate, CandidateSet
from psorr.hypotheses.psg import PsgCandidates
from psorr.types import Detection, PointCloud

_NAMES = ["chassis", "bracket"]


class _Acceptance:
    """Accepts every candidate of the models in ``accepts``, and records the candidates it was asked to fit."""

    library = SimpleNamespace(names=_NAMES)

    def __init__(self, accepts: set[str]):
        self.accepts, self.asked = accepts, []

    def __call__(self, view, candidates, claims):
        self.asked.append([(_NAMES[c.model], c.score) for c in candidates])
        found = [Detection(_NAMES[c.model], c.T_cloud_model, c.score) for c in candidates
                 if _NAMES[c.model] in self.accepts]
        claims.detections.extend(found)
        return found


class _Explained:
    """A detection explains the primitives whose points are at x = 0 (primitives 0 and 1)."""

    def explain(self, detections, points):
        return bool(detections) and bool(np.all(points[:, 0] == 0))


def _scene():
    points = np.array([[0.0, 0, 1], [0.0, 1, 1], [1.0, 0, 1]])
    return PointCloud(points), SimpleNamespace(labels=np.array([0, 1, 2]))


def _found(rows):
    """rows: (model index, the scene surface its pose explains, scene primitives) per candidate."""
    candidates = tuple(Candidate(m, np.eye(4), score=i / 10) for i, (m, _, _) in enumerate(rows))
    return PsgCandidates(CandidateSet(candidates, len(rows)), 0, 0, tuple(v for _, _, v in rows),
                         tuple(float(e) for _, e, _ in rows))


def test_candidates_are_fitted_by_the_surface_they_explain_and_not_on_another_models_primitives():
    cloud, scene = _scene()
    acceptance = _Acceptance({"chassis"})
    found = _found([(1, 5, (2,)), (0, 9, (0, 1)), (1, 4, (0, 1)), (0, 6, (0, 1)), (1, 3, (1, 2))])
    claims = SimpleNamespace(detections=[])
    detections = accept_by_rank(acceptance, _Explained(), None, cloud, scene, found, claims)
    # The chassis explaining most goes first; then the chassis's second (its own model may be turned over
    # onto the same faces), the bracket on a primitive no detection explains, and not the bracket on the
    # chassis's primitives; then the bracket on primitive 1, explained, and 2, not.
    assert acceptance.asked == [[("chassis", 0.1)], [("chassis", 0.3)], [("bracket", 0.0)], [("bracket", 0.4)]]
    assert [d.model for d in detections] == ["chassis", "chassis"]


def test_with_no_detection_every_candidate_is_fitted_and_ties_keep_their_order():
    cloud, scene = _scene()
    acceptance = _Acceptance(set())
    found = _found([(0, 1, (0, 1)), (1, 2, (0, 1)), (0, 1, (0,)), (1, 1, (1,))])
    assert accept_by_rank(acceptance, _Explained(), None, cloud, scene, found, SimpleNamespace(detections=[])) == []
    assert acceptance.asked == [[("bracket", 0.1)], [("chassis", 0.0)], [("chassis", 0.2)], [("bracket", 0.3)]]
