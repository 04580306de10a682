"""Which detection explains which pixels: conflicting detections are settled by score, not by
which search found them first.

A scene's detections come from several searches in turn (pair rounds, single faces, a finer second
look). A wrong pose found early (an L bracket laid over a circuit board) must not keep the pixels
from the right one found later (the board, from its single face): the recognizer keeps the better of
two detections that explain the same pixels, whichever came first.
"""

from __future__ import annotations

import numpy as np

from psorr.types import Detection


class PixelClaims:
    """The accepted detections of one scene, and the claim cells (``n_blocks`` of them: pixel blocks as
    wide as 4x4 pixels of a 640-wide image, SceneView.claim_cell_of) each was the first to explain.

    A candidate whose supported blocks are held by others beyond ``max_shared`` (a share of its
    blocks) takes them over only when it scores higher than every detection it must displace to
    get under that share; the displaced detections are dropped with all their blocks.
    """

    def __init__(self, n_blocks: int, max_shared: float):
        self.owner = np.full(n_blocks, -1, dtype=np.int64)  # index into _entries, -1 for none
        self.max_shared = max_shared
        self._entries: list[tuple[float, Detection] | None] = []

    @property
    def detections(self) -> list[Detection]:
        """The detections that stand, in the order they were accepted."""
        return [e[1] for e in self._entries if e is not None]

    def rivals(self, blocks: np.ndarray, score: float) -> list[int] | None:
        """The detections a candidate with ``blocks`` (its supported blocks) and ``score`` must displace:
        [] if it conflicts with none, None if it loses to one of them."""
        held = self.owner[blocks]
        held = held[held >= 0]
        if len(held) <= self.max_shared * len(blocks):
            return []
        owners, counts = np.unique(held, return_counts=True)
        remaining, displaced = len(held), []
        # The largest overlaps first: displacing them frees the most, so the fewest are displaced.
        for k in np.argsort(-counts, kind="stable"):
            if remaining <= self.max_shared * len(blocks):
                break
            rival = int(owners[k])
            if self._entries[rival][0] >= score:
                return None
            displaced.append(rival)
            remaining -= counts[k]
        return displaced

    def add(self, detection: Detection, blocks: np.ndarray, score: float, displaced: list[int]) -> None:
        """Accept ``detection``: drop the ``displaced`` (from :meth:`rivals`), and give it ``blocks`` no one holds."""
        for rival in displaced:
            self.owner[self.owner == rival] = -1
            self._entries[rival] = None
        index = len(self._entries)
        self._entries.append((score, detection))
        free = blocks[self.owner[blocks] < 0]
        self.owner[free] = index
