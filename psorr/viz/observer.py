"""What a recognition did, stage by stage, for whoever watches it: a :class:`~psorr.viz.rerun_log.RerunLogger`,
or a user's own subclass.

The recognizer's stages report to the observer that :func:`observed_by` made current for the call; without
one they report to a :class:`RecognitionObserver`, which does nothing, so watching costs nothing when nobody
watches. A context variable carries it rather than an argument through every stage, since the stages that
report (decomposition, each hypothesis source, acceptance) sit several calls deep and most callers never watch.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from contextvars import ContextVar

import numpy as np


class RecognitionObserver:
    """Receives each stage of a recognition as it happens. Every method does nothing here; override those
    you want. Clouds, poses and planes are in the cloud's frame, metres."""

    def cloud(self, cloud) -> None:
        """The input :class:`psorr.types.PointCloud`, as the recognizer works on it (thinned to its sampling)."""

    def table(self, plane: np.ndarray | None) -> None:
        """The supporting plane (a, b, c, d), the sensor on its positive side, or None when there is none."""

    def decomposition(self, name: str, cloud, scene) -> None:
        """A decomposition (:class:`psorr.decomposition.Decomposition`, labels indexing ``cloud``'s points; None
        when there was too little to decompose) of the pass ``name``: ``"scene"`` for what stands on the
        table, ``"detail"`` for the finer second look at what no detection explains."""

    def candidates(self, candidates, library) -> None:
        """The :class:`psorr.hypotheses.candidates.Candidate` s one search round (PSORR's pairs, PSG's cliques,
        single primitives, outlines, an earlier look's detections) hands to acceptance, with the scores their
        screening gave them; ``library`` is the recognizer's, whose ``models[c.model]`` each is of."""

    def rejected(self, model: str, T_cloud_model: np.ndarray, reason: str) -> None:
        """A candidate of ``model`` that acceptance turned down at ``T_cloud_model`` (4, 4), and why."""

    def detections(self, detections, library) -> None:
        """The accepted :class:`psorr.types.Detection` s of the whole recognition, in the cloud of :meth:`cloud`."""

    def stage_ms(self, name: str, ms: float) -> None:
        """How long a stage (``"decomposition"``, ``"total"``, ...) took, in milliseconds."""


_NOBODY = RecognitionObserver()
_CURRENT: ContextVar[RecognitionObserver] = ContextVar("psorr_recognition_observer", default=_NOBODY)


def observer() -> RecognitionObserver:
    """The observer of the recognition in progress (one that does nothing when nobody watches)."""
    return _CURRENT.get()


def watched() -> bool:
    """Does someone watch the recognition in progress? Stages skip work only an observer needs otherwise."""
    return _CURRENT.get() is not _NOBODY


@contextlib.contextmanager
def observed_by(watcher: RecognitionObserver | None) -> Iterator[RecognitionObserver]:
    """Make ``watcher`` (None: nobody) the observer of the stages run inside the block."""
    if watcher is not None and not isinstance(watcher, RecognitionObserver):
        from psorr.errors import InvalidInputError

        raise InvalidInputError(f"an observer must be a psorr.viz.RecognitionObserver (such as "
                                f"psorr.viz.RerunLogger), got {type(watcher).__name__}")
    token = _CURRENT.set(watcher or _NOBODY)
    try:
        yield _CURRENT.get()
    finally:
        _CURRENT.reset(token)
