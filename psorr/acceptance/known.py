"""Parts an earlier look found, looked for again where they were: a robot cell that looks again after each
pick sees the same table with one part gone and perhaps a neighbour nudged.

Each known detection becomes a candidate at its pose and goes through acceptance like any other (ICP from
there, the point check, the claims), so a part nudged by millimetres is followed and a part gone is dropped.
The standing points the followed parts explain then leave the search, which decomposes and pairs only what
is new or has moved (``Recognizer.recognize(..., known=...)``).
"""

from __future__ import annotations

from collections.abc import Sequence

from psorr.errors import InvalidInputError
from psorr.hypotheses.candidates import Candidate, CandidateSet
from psorr.library.models import ModelLibrary
from psorr.types import Detection


def known_candidates(library: ModelLibrary, known: Sequence[Detection]) -> CandidateSet:
    """The ``known`` detections (an earlier look's, same sensor frame) as candidates of ``library``'s models.

    Raises:
        InvalidInputError: ``known`` is not a sequence of Detections of the library's models.
    """
    if isinstance(known, Detection) or not isinstance(known, Sequence):
        raise InvalidInputError(f"recognize()'s known must be a sequence of Detections (an earlier look's "
                                f"detections), got {type(known).__name__}")
    out = []
    for k, d in enumerate(known):
        if not isinstance(d, Detection):
            raise InvalidInputError(f"recognize()'s known[{k}] must be a Detection, got {type(d).__name__}")
        if d.model not in library.names:
            raise InvalidInputError(f"recognize()'s known[{k}] is of the model {d.model!r}, which the library does "
                                    f"not hold (it holds {', '.join(library.names)})")
        out.append(Candidate(library.names.index(d.model), d.T_cloud_model))
    return CandidateSet(tuple(out))
