"""Seeing what the recognizer did: pictures of decompositions coloured by primitive with their shape graph,
and of detections drawn over a cloud (:mod:`~psorr.viz.render`); and every stage of a recognition as it
happens (:class:`RecognitionObserver`), recorded for the Rerun viewer by :class:`RerunLogger` (the
``psorr[viz]`` extra; rerun is imported only when a logger is made)."""

from psorr.viz.observer import RecognitionObserver, observed_by
from psorr.viz.rerun_log import RerunLogger

__all__ = ["RecognitionObserver", "RerunLogger", "observed_by"]
