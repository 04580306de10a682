"""Which detection explains which pixels: conflicting detections are settled by score, not by
which search found them first.

A scene's detections come from several searches in turn (pair rounds, single faces, a finer second
look). A wrong pose found early (an L bracket laid over a circuit board) must not keep the pixels
from the right one found later (the board, from its single face): the recognizer keeps the better of
two detections that explain the same pixels, whichever came first. A detection found later that
covers much of an earlier one's pixels conflicts with it too, although the earlier one holds little
of its own: a bracket accepted on a chassis' wall, and the chassis found after it.

Each conflict is put to the scene first, when a judge is given (:class:`~psorr.acceptance.render_judge.RenderJudge`):
the detection whose render agrees clearly better with the measured depth stays. Only when the view cannot
tell the two apart do the scores and pixel counts below decide.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from psorr.types import Detection, Rival
from psorr.viz.observer import observer

_CLEARLY_MORE = 1.25  # a candidate explains more than a detection it covers only by this factor


class PixelClaims:
    """The accepted detections of one scene, and the claim cells (``n_blocks`` of them: pixel blocks as
    wide as 4x4 pixels of a 640-wide image, SceneView.claim_cell_of) each was the first to explain.

    A candidate whose supported blocks are held by others beyond ``max_shared`` (a share of its
    blocks) takes them over only when it beats every detection it must displace to get under that
    share; the displaced detections are dropped with all their blocks. A candidate that covers more
    than ``max_shared`` of a detection's own blocks conflicts with it as well, and displaces it only
    when it explains more: more blocks, each weighted by its detection's score. Either way, a candidate
    that covers most of a detection's blocks also beats it by explaining clearly more blocks
    (_CLEARLY_MORE times), each weighted by how clean the detection is: the share of its checked
    points that the sensor does not see through. With a ``judge`` (``prefer(model_a, T_a, model_b, T_b)``
    giving 1, -1 or 0), its verdict on the candidate's pose against the rival's comes before all of these,
    whenever it gives one. When it gives none between two models' poses that hold most of each other's
    blocks, the one kept reports the other as a :class:`~psorr.types.Rival` (:meth:`reported`).
    """

    def __init__(self, n_blocks: int, max_shared: float, judge=None):
        self.owner = np.full(n_blocks, -1, dtype=np.int64)  # index into _entries, -1 for none
        self.max_shared = max_shared
        self.judge = judge
        self._entries: list[tuple[float, Detection, float] | None] = []  # score, detection, weight
        self._blocks: list[np.ndarray] = []  # each entry's supported blocks, held or not
        self._rivals: list[list[Rival]] = []  # each entry's rivals the judge could not tell it from
        self.ties: list[int] = []  # the entries the last rivals() call tied with: another model, the same pixels

    @property
    def detections(self) -> list[Detection]:
        """The detections that stand, in the order they were accepted."""
        return [e[1] for e in self._entries if e is not None]

    def reported(self) -> list[Detection]:
        """:attr:`detections`, each with the rivals the view could not rule out."""
        return [replace(e[1], rivals=tuple(rivals)) if rivals else e[1]
                for e, rivals in zip(self._entries, self._rivals) if e is not None]

    def lost_tie(self, candidate: Detection, score: float) -> None:
        """Report ``candidate`` (with ``score``), turned away after the last :meth:`rivals` call, as a rival of
        the detections it tied with there."""
        for rival in self.ties:
            if self._entries[rival] is not None:
                _keep_best(self._rivals[rival], Rival(candidate.model, candidate.T_cloud_model, score))

    def rivals(self, blocks: np.ndarray, score: float, clean: float | None = None,
               candidate: Detection | None = None) -> list[int] | None:
        """The detections a candidate with ``blocks`` (its supported blocks), ``score`` and ``clean`` (the
        share of its checked points not seen through; its score when None) must displace: [] if it
        conflicts with none, None if it loses to one of them. ``candidate`` (its model and pose) is what
        the judge compares, if there is one."""
        blocks = np.unique(blocks)
        self.ties = []
        weight = _weight(score, clean, len(blocks))
        held = self.owner[blocks]
        held = held[held >= 0]
        covered = np.zeros(len(self.owner), dtype=bool)
        covered[blocks] = True
        displaced = []
        if len(held) > self.max_shared * len(blocks):
            owners, counts = np.unique(held, return_counts=True)
            remaining = len(held)
            # The largest overlaps first: displacing them frees the most, so the fewest are displaced.
            for k in np.argsort(-counts, kind="stable"):
                if remaining <= self.max_shared * len(blocks):
                    break
                rival = int(owners[k])
                verdict = self._verdict(candidate, rival, blocks, covered)
                if verdict < 0 or verdict == 0 and not (
                        self._entries[rival][0] < score
                        or self._covers(rival, covered) and self._explains_clearly_more(rival, weight)):
                    return None
                displaced.append(rival)
                remaining -= counts[k]
        for rival, entry in enumerate(self._entries):
            if entry is None or rival in displaced:
                continue
            if self._covers(rival, covered):
                own = self._blocks[rival]
                # The candidate explains much of what the rival does, and maybe more: the one that explains
                # more, blocks weighted by score, stays. By score alone a bracket posed on a chassis' wall
                # (0.71 of it seen, 57 blocks) dropped the true chassis (0.48, 180 blocks) in a 1280x720 view.
                explains_more = entry[0] * len(own) < score * len(blocks)
                verdict = self._verdict(candidate, rival, blocks, covered)
                if verdict < 0 or verdict == 0 and not (explains_more or self._explains_clearly_more(rival, weight)):
                    return None
                displaced.append(rival)
        return displaced

    def _verdict(self, candidate: Detection | None, rival: int, blocks: np.ndarray, covered: np.ndarray) -> int:
        """The judge's verdict on ``candidate`` (its ``blocks``, and ``covered`` marking them) against the
        ``rival`` detection: 1, -1, or 0 (none). No verdict between two models' poses that hold most of each
        other's blocks is a tie, noted in :attr:`ties`."""
        if self.judge is None or candidate is None:
            return 0
        held = self._entries[rival][1]
        verdict = self.judge.prefer(candidate.model, candidate.T_cloud_model, held.model, held.T_cloud_model)
        if verdict == 0 and candidate.model != held.model:
            shared = covered[self._blocks[rival]].sum()
            if shared > self.max_shared * max(len(blocks), len(self._blocks[rival])):
                self.ties.append(rival)
        return verdict

    def _covers(self, rival: int, covered: np.ndarray) -> bool:
        """Do the ``covered`` blocks (a candidate's) hold more than ``max_shared`` of the rival's own?"""
        own = self._blocks[rival]
        return covered[own].sum() > self.max_shared * len(own)

    def _explains_clearly_more(self, rival: int, weight: float) -> bool:
        """Does a candidate covering the rival (:meth:`_covers`), with ``weight`` (blocks times how clean it is),
        exceed the rival's weight by _CLEARLY_MORE? Scored by what it shows,
        a chassis 37% in view under an arm (0.36; but 0.97 of what the sensor could see of it is measured,
        0.03 seen through, 139 blocks) lost to the two brackets posed on it (0.70 and 0.73, 0.87-0.89 clean,
        99 and 91 blocks), by score and by score times blocks alike."""
        return weight > _CLEARLY_MORE * self._entries[rival][2]

    def add(self, detection: Detection, blocks: np.ndarray, score: float, displaced: list[int],
            clean: float | None = None) -> None:
        """Accept ``detection``: drop the ``displaced`` (from :meth:`rivals`), and give it ``blocks`` no one
        holds; ``score`` and ``clean`` as for :meth:`rivals`."""
        tied: list[Rival] = []
        for rival in displaced:
            held = self._entries[rival][1]
            if rival in self.ties:
                _keep_best(tied, Rival(held.model, held.T_cloud_model, self._entries[rival][0]))
            observer().rejected(held.model, held.T_cloud_model, "displaced by a better detection")
            self.owner[self.owner == rival] = -1
            self._entries[rival] = None
        self._rivals.append(tied)
        index = len(self._entries)
        self._blocks.append(np.unique(blocks))
        self._entries.append((score, detection, _weight(score, clean, len(self._blocks[-1]))))
        free = blocks[self.owner[blocks] < 0]
        self.owner[free] = index


@dataclass(frozen=True, eq=False)
class SearchResult:
    """What one recognize() call found, in the order accepted, and what it cost: hypotheses screened, the
    ms their screening took, and the ms spent decomposing the scene; for PSG, QPBO's nodes and how many
    it left unlabelled."""

    detections: tuple[Detection, ...]
    hypotheses: int
    verify_ms: float
    decomposition_ms: float
    qpbo_nodes: int = 0
    qpbo_unlabelled: int = 0


@dataclass
class SearchTally:
    """What one recognize() call has found so far, and its cost: ``claims`` holds the detections and the
    claim cells they explain."""

    claims: PixelClaims
    decomposition_ms: float = 0.0
    hypotheses: int = 0
    verify_ms: float = 0.0
    qpbo_nodes: int = 0
    qpbo_unlabelled: int = 0

    @property
    def detections(self) -> list[Detection]:
        return self.claims.detections

    def add(self, hypotheses: int, verify_ms: float) -> None:
        self.hypotheses += hypotheses
        self.verify_ms += verify_ms

    def result(self) -> SearchResult:
        return SearchResult(tuple(self.claims.reported()), self.hypotheses, self.verify_ms, self.decomposition_ms,
                            self.qpbo_nodes, self.qpbo_unlabelled)


def _weight(score: float, clean: float | None, n_blocks: int) -> float:
    """Blocks weighted by how clean a pose is (its score when ``clean`` is None): what it explains."""
    return (score if clean is None else clean) * n_blocks


def _keep_best(rivals: list[Rival], rival: Rival) -> None:
    """Add ``rival`` to ``rivals``, which hold one pose per model: its best by score."""
    for k, held in enumerate(rivals):
        if held.model == rival.model:
            if rival.score > held.score:
                rivals[k] = rival
            return
    rivals.append(rival)
