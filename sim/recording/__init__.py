"""Recording an episode: the MP4 of the cell as it runs (:mod:`~sim.recording.recorder`), the PNG contact sheet
of its looks and grasps (:mod:`~sim.recording.sheet`), and a Rerun recording of its bodies, looks, grasp plans,
stops and picks on a simulated-time timeline (:mod:`~sim.recording.rerun_episode`, the ``psorr[viz]`` extra)."""

from sim.recording.recorder import EpisodeRecorder
from sim.recording.rerun_episode import RerunEpisodeRecorder

__all__ = ["EpisodeRecorder", "RerunEpisodeRecorder"]
