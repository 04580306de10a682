"""What a hypothesis stage hands on to acceptance: screened candidate poses, and what screening them cost."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Candidate:
    """One screened pose hypothesis: the library's ``model`` (an index into ``ModelLibrary.models``) at
    ``T_cloud_model`` (4, 4), mapping model coordinates (metres) into the cloud's frame, and the score its
    screening gave it (the bounding-box fitness of pairs and cliques, the coarse point check's of single
    primitives), or None when its source scores none; ``region``: the patch of points standing on the table it
    was made for (the outline's, numbered per scene), or None."""

    model: int
    T_cloud_model: np.ndarray
    score: float | None = None
    region: int | None = None


@dataclass(frozen=True, eq=False)
class CandidateSet:
    """The candidates a hypothesis stage passes on, best first, with the number of hypotheses it screened
    to choose them and the milliseconds the screening (verification, not the making of poses) took."""

    candidates: tuple[Candidate, ...] = ()
    hypotheses: int = 0
    verify_ms: float = 0.0
    regions: int = 0  # the patches standing on the table it searched (the outline's), with a candidate or not

    def __len__(self) -> int:
        return len(self.candidates)

    @classmethod
    def chosen(cls, models: np.ndarray, poses: np.ndarray, order, hypotheses: int, verify_ms: float,
               scores: np.ndarray | None = None) -> CandidateSet:
        """The candidates ``order`` picks (indices into ``models`` (K,), ``poses`` (K, 4, 4) and their screening
        ``scores`` (K,), if any), in that order."""
        return cls(tuple(Candidate(int(models[k]), poses[k], None if scores is None else float(scores[k]))
                         for k in order), hypotheses, verify_ms)
