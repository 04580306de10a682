"""Recording an episode: the MP4 of the cell as it runs (:mod:`~sim.recording.recorder`) and the PNG
contact sheet of its looks and grasps (:mod:`~sim.recording.sheet`)."""

from sim.recording.recorder import EpisodeRecorder

__all__ = ["EpisodeRecorder"]
