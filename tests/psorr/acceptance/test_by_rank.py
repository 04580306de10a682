"""PSG's rank-by-rank acceptance (psorr.acceptance.by_rank), with acceptance and the explained surfaces
stood in for."""

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
    """rows: (model index, its rank, scene primitives) per candidate, in order; the rank is read off the order,
    and given here for the reader."""
    candidates = tuple(Candidate(m, np.eye(4), score=i / 10) for i, (m, _, _) in enumerate(rows))
    return PsgCandidates(CandidateSet(candidates, len(rows)), 0, 0, tuple(v for _, _, v in rows))


def test_a_later_rank_of_another_model_on_explained_primitives_is_not_fitted():
    cloud, scene = _scene()
    acceptance = _Acceptance({"chassis"})
    found = _found([(0, 0, (0, 1)), (1, 0, (2,)), (0, 1, (0, 1)), (1, 1, (0, 1)), (1, 2, (1, 2))])
    claims = SimpleNamespace(detections=[])
    detections = accept_by_rank(acceptance, _Explained(), None, cloud, scene, found, claims)
    # Rank 0 fits both models' best; rank 1 the chassis's second (its own model), not the bracket on the
    # chassis's primitives; rank 2 the bracket on a primitive no detection explains.
    assert acceptance.asked == [[("chassis", 0.0), ("bracket", 0.1)], [("chassis", 0.2)], [("bracket", 0.4)]]
    assert [d.model for d in detections] == ["chassis", "chassis"]


def test_with_no_detection_every_rank_is_fitted():
    cloud, scene = _scene()
    acceptance = _Acceptance(set())
    found = _found([(0, 0, (0, 1)), (1, 0, (0, 1)), (0, 1, (0,)), (1, 1, (1,))])
    assert accept_by_rank(acceptance, _Explained(), None, cloud, scene, found, SimpleNamespace(detections=[])) == []
    assert [len(turn) for turn in acceptance.asked] == [2, 2]
