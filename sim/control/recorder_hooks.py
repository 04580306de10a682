"""What an episode tells a recorder as it happens (:class:`Recorder`): every physics step, each look, each grasp
plan, each protective stop, each grasp and each pick's outcome."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import mujoco

from sim.world import World

if TYPE_CHECKING:  # perception.py imports this module's users; only the annotations need these
    from psorr.library.models import ModelLibrary
    from psorr.viz.observer import RecognitionObserver
    from sim.skills.grasp_planning import GraspPlan
    from sim.skills.judging import PickResult
    from sim.skills.perception import Look


class Recorder(Protocol):
    """Receives the episode as it happens: :class:`sim.recording.recorder.EpisodeRecorder` writes a video and a
    contact sheet, :class:`sim.recording.rerun_episode.RerunEpisodeRecorder` a Rerun recording. Every method
    does nothing here; a recorder that subclasses this overrides those it wants."""

    def tick(self, world: World, data: mujoco.MjData) -> None:
        """After every physics step (the recorder decides which to keep)."""

    def looked(self, world: World, data: mujoco.MjData, look: Look, library: ModelLibrary | None) -> None:
        """After each look, with the model library (None for the oracle)."""

    def planned(self, world: World, data: mujoco.MjData, part: str, plan: GraspPlan) -> None:
        """When a grasp of ``part`` is planned, before the arm moves to it."""

    def stopped(self, world: World, data: mujoco.MjData) -> None:
        """When the monitor holds the arm because someone reaches over the table (a protective stop)."""

    def grasped(self, world: World, data: mujoco.MjData, part: str) -> None:
        """When the gripper has closed on ``part`` (before the lift tells whether the grasp holds)."""

    def picked(self, world: World, data: mujoco.MjData, result: PickResult) -> None:
        """When a pick has ended, placed or not."""

    def recognition_observer(self) -> RecognitionObserver | None:
        """What watches each look's recognition, stage by stage (:class:`psorr.viz.RecognitionObserver`), or
        None."""


class Recorders(Recorder):
    """Several recorders as one (a video and a Rerun recording of the same episode): each call goes to each."""

    def __init__(self, *recorders: Recorder):
        self.recorders = recorders

    def tick(self, world, data):
        for r in self.recorders:
            r.tick(world, data)

    def looked(self, world, data, look, library):
        for r in self.recorders:
            r.looked(world, data, look, library)

    def planned(self, world, data, part, plan):
        for r in self.recorders:
            r.planned(world, data, part, plan)

    def stopped(self, world, data):
        for r in self.recorders:
            r.stopped(world, data)

    def grasped(self, world, data, part):
        for r in self.recorders:
            r.grasped(world, data, part)

    def picked(self, world, data, result):
        for r in self.recorders:
            r.picked(world, data, result)

    def recognition_observer(self):
        return next((o for r in self.recorders if (o := r.recognition_observer()) is not None), None)


def combined(*recorders: Recorder | None) -> Recorder | None:
    """The recorders given that are not None as one: None for none, itself for one."""
    given = [r for r in recorders if r is not None]
    return None if not given else given[0] if len(given) == 1 else Recorders(*given)
