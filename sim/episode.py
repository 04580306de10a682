"""Pick-and-place episodes: look, decide, pick, until every part has had its pick or the robot gives up.

Each round the robot looks at the cell (:class:`sim.skills.perception.Perception`): with ``poses=
PoseSource.RECOGNIZED`` it renders the Kinect and runs PSORR; with ``PoseSource.ORACLE`` it takes the
simulator's true poses (and, with the human about, only checks whether someone is reaching in). Then:

- someone is reaching over the table: wait and look again;
- no remaining part was returned with a score of at least ``MIN_SCORE`` (hidden, or the
  recognizer is unsure): wait and look again, up to ``MAX_BLIND_LOOKS`` looks in a row;
- otherwise pick the first remaining part, in task order, from the pose that look returned (of a part
  placed several times, the instance nearest the pose; see :meth:`Episode.estimates`).

With ``WorldConfig.pick`` only the parts it names are picked, in its order; one named with a colour
(``"red idler"``) is picked from a detection the look saw in that colour.

A part is picked at most once. While the arm moves, the monitor stops it whenever someone
reaches in (:mod:`sim.control.cell`). A look costs ``THINK_S`` of simulated time, during which the arm
holds still, so the human keeps moving while the robot thinks.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from types import MappingProxyType

import mujoco
import numpy as np

from sim.control.cell import ArmCell
from sim.control.recorder_hooks import Recorder
from sim.errors import SimInputError, WorkspaceBlockedError
from sim.modes import PoseSource, parse_mode
from sim.people.human import ReachingHuman
from sim.skills.judging import PickResult, fixture_error, pose_error, resting_on_table
from sim.skills.perception import MONITOR_OCCUPIED, Estimate, Look, Perception
from sim.skills.perception_params import PerceptionParams
from sim.skills.pick import pick_and_place
from sim.world import World
from sim.world.config import pick_target

__all__ = ["Episode", "EpisodeResult", "PickResult", "fixture_error", "pick_and_place", "pose_error", "run_episode"]

MIN_SCORE = 0.3  # detections scoring less are not trusted enough to grasp from
MAX_BLIND_LOOKS = 5  # looks in a row with nothing pickable before the rest of the parts are given up
WAIT_S = 0.5  # s waited before looking again
THINK_S = 0.5  # s of simulated time a look (render and recognition) takes
MAX_EPISODE_S = 240.0  # s of simulated time after which the remaining parts are given up
PLACED_RADIUS = 0.02  # m: a pose this near a filled fixture's is the part placed there (placing is within 5 mm)


@dataclass(frozen=True)
class EpisodeResult:
    """One episode: a :class:`PickResult` per workpiece (picked order, then the ones never picked).

    Attributes:
        picks: the picks.
        wall_s: wall time of the episode (s); sim_s: simulated time (s).
        looks: looks taken; occupied_looks: how often a look, or the check just before a pick,
            found someone reaching in (each time the robot waited).
        protective_stops, stopped_s: times, and total seconds, the monitor held the arm.
        min_human_clearance_mm: least distance between the arm's and the human's geoms
            (simulator truth; inf without the human).
    """

    picks: tuple[PickResult, ...]
    wall_s: float
    sim_s: float = 0.0
    looks: int = 0
    occupied_looks: int = 0
    protective_stops: int = 0
    stopped_s: float = 0.0
    min_human_clearance_mm: float = math.inf


class Episode:
    """A seeded episode in progress; :meth:`run` plays the scripted policy, an env can drive it step by step.

    Args:
        world: the cell; it is reset to home here and stepped in place.
        rng: the only randomness (the human's reaches, then the sensor noise).
        poses: a :class:`~sim.modes.PoseSource` or its string, ``"recognized"`` (PSORR on the Kinect's
            cloud) or ``"oracle"`` (true poses).
        occluder: the human reaches over the table on a seeded timeline; the robot watches for it.
        recorder: gets every physics step and each look (see :mod:`sim.recording.recorder`), or None.
        rgb: looks also render the colour image; default: only when there is a recorder to show it.
        colours: looks name each detection's colour; default: when ``WorldConfig.pick`` names a colour.
        perception: the looks' recognizer and sensor noise (:class:`PerceptionParams`; default PSORR, Kinect v1).

    Call :meth:`close` when done (or use it as a context manager): it frees the renderers.
    """

    def __init__(self, world: World, rng: np.random.Generator, poses: PoseSource | str = PoseSource.RECOGNIZED,
                 occluder: bool = False, recorder: Recorder | None = None, rgb: bool | None = None,
                 colours: bool | None = None, perception: PerceptionParams | None = None):
        poses = parse_mode(PoseSource, poses, "poses")
        if occluder and not world.occluder_geoms:
            raise SimInputError("occluder=True needs a world built with WorldConfig(occluder=True)")
        self.world, self.rng, self.poses, self.recorder = world, rng, poses, recorder
        world.reset()
        human = None
        if occluder:
            targets = [world.body_pose(p)[:2, 3] for p in world.workpieces]
            human = ReachingHuman(rng, world.config.table_size, world.table_top, targets=targets,
                                  eye=world.T_world_camera[:3, 3], gap_s=world.config.reach_gap_s)
        self.human = human
        self.remaining, self.wanted_colour = _wanted(world)
        recognizing = poses is PoseSource.RECOGNIZED
        rgb = recorder is not None if rgb is None else rgb
        colours = any(self.wanted_colour.values()) if colours is None else colours
        watcher = recorder.recognition_observer() if recorder is not None else None
        self.perception = Perception(world, rng, recognize=recognizing, rgb=rgb, colours=colours,
                                     params=perception, observer=watcher) \
            if recognizing or occluder else None
        self.cell = ArmCell(world, human=human, monitor=self.perception if occluder else None, recorder=recorder)
        self.picks: list[PickResult] = []
        self.looks = self.occupied_looks = 0
        self._start = time.perf_counter()

    @property
    def library(self):
        """The recognizer's model library, or None in oracle mode."""
        return self.perception.library if self.perception is not None else None

    def look(self) -> Look:
        """Swing the arm out of the view and look at the cell; the look costs ``THINK_S`` of simulated time."""
        self.cell.clear_the_view()
        data = self.world.data
        mujoco.mj_forward(self.world.model, data)
        if self.poses is PoseSource.RECOGNIZED:
            look = self.perception.look(data, self.cell.holding)
        else:
            watched = self.cell.monitor is not None
            intruding = self.perception.monitor_intruding(data, self.cell.holding) if watched else 0
            occupied = watched and intruding >= MONITOR_OCCUPIED
            truth = {}
            for p in () if occupied else self.remaining:
                truth.setdefault(self.world.part_types[p], []).append(
                    Estimate(self.world.body_pose(p), 1.0, colour=self.world.colour_name(p)))
            truth = {kind: tuple(estimates) for kind, estimates in truth.items()}
            look = Look(None, (), MappingProxyType(truth), intruding, occupied)
        self.looks += 1
        self.occupied_looks += look.occupied
        if self.recorder is not None:
            self.recorder.looked(self.world, data, look, self.library)
        self.cell.hold(THINK_S)
        return look

    def estimate(self, look: Look, part: str) -> Estimate | None:
        """The estimate to grasp ``part`` (a body) from, as :meth:`estimates` assigns them; None if it has none."""
        return self.estimates(look).get(part)

    def estimates(self, look: Look) -> dict[str, Estimate]:
        """The remaining bodies' estimates in ``look``: each part's detections that score at least MIN_SCORE and
        stand upright on the table (parts rest there; anything else is a mistake), best first, each given to
        the nearest remaining instance of its part that has none yet and is wanted in the colour the look saw
        it in (any colour, unless ``WorldConfig.pick`` names one).

        Which instance a pose is of is read from the simulator: it names the body the pick is graded against
        and whose fixture it fills (the instances' fixtures are alike). The robot moves on the pose alone."""
        out: dict[str, Estimate] = {}
        for kind, found in look.estimates.items():
            free = [p for p in self.remaining if self.world.part_types[p] == kind]
            for estimate in found:
                if not free:
                    break
                if self._already_placed(estimate.T_world_part):
                    continue
                wanted = [p for p in free if self.wanted_colour[p] in (None, estimate.colour)]
                if wanted and estimate.score >= MIN_SCORE and resting_on_table(self.world, estimate.T_world_part,
                                                                               free[0]):
                    at = estimate.T_world_part[:3, 3]
                    body = min(wanted, key=lambda p: np.linalg.norm(self.world.body_pose(p)[:3, 3] - at))
                    out[body] = estimate
                    free.remove(body)
        return out

    def _already_placed(self, T_world_part: np.ndarray) -> bool:
        """Whether a pose lies where the robot has put a part: in the tote, or on a fixture it filled (the robot
        knows its places; a part of a kind placed there may be seen again, and is not to be picked twice)."""
        world, at = self.world, T_world_part[:3, 3]
        if world.tote is not None:
            inside = np.linalg.inv(world.T_world_tote)[:2] @ np.append(at, 1.0)
            if world.tote.holds(inside[None], margin=world.config.tote_wall[0]):
                return True
        filled = [world.T_world_fixtures[p.part][:3, 3] for p in self.picks
                  if p.grasped and p.part in world.T_world_fixtures]
        return any(np.linalg.norm(at[:2] - F[:2]) < PLACED_RADIUS for F in filled)

    def wait(self, seconds: float = WAIT_S) -> None:
        self.cell.hold(seconds)

    def pick(self, part: str, T_world_part: np.ndarray, looks: int = 1,
             alternatives: tuple[np.ndarray, ...] = ()) -> PickResult:
        """Pick-and-place ``part`` from the pose (4, 4, world); it leaves the remaining list whatever happens.
        With ``alternatives`` (the pose's near-symmetric twins the look could not rule out) and
        recognition on, the robot looks at the part in its hand before placing it (:mod:`sim.skills.in_hand`)."""
        if part not in self.remaining:
            raise SimInputError(f"{part!r} is not waiting to be picked; remaining: {self.remaining}")
        result = pick_and_place(self.world, part, T_world_part, self.cell, alternatives,
                                self.perception if self.poses is PoseSource.RECOGNIZED else None)
        result = replace(result, looks=looks)
        self.remaining.remove(part)
        self.picks.append(result)
        if self.recorder is not None:
            self.recorder.picked(self.world, self.world.data, result)
        return result

    def give_up(self, why: str) -> None:
        """Record every remaining part as not picked, with ``why``."""
        self.picks.extend(_not_picked(part, why) for part in self.remaining)
        self.remaining = []

    def run(self) -> EpisodeResult:
        """The scripted policy of the module docstring, to the end of the episode."""
        blind = looks = 0
        try:
            while self.remaining:
                if self.world.data.time > MAX_EPISODE_S:
                    self.give_up(f"not picked within {MAX_EPISODE_S:.0f} s")
                    break
                look = self.look()
                looks += 1
                if look.occupied:
                    self.wait()
                    continue
                assigned = self.estimates(look)
                choice = next(((p, assigned[p]) for p in self.remaining if p in assigned), None)
                if choice is None:
                    blind += 1
                    if blind >= MAX_BLIND_LOOKS:
                        self.give_up(f"not recognised in {blind} looks in a row")
                        break
                    self.wait()
                    continue
                if self.cell.monitor is not None and self.perception.occupied(self.world.data, self.cell.holding):
                    # They started reaching in while the robot thought: a plan made now would have to
                    # steer round their arm, and the pose may be stale when they withdraw.
                    self.occupied_looks += 1
                    self.wait()
                    continue
                part, estimate = choice
                self.pick(part, estimate.T_world_part, looks=looks, alternatives=estimate.alternatives)
                blind = looks = 0
        except WorkspaceBlockedError as exc:
            self.give_up(str(exc))
        return self.result()

    def result(self) -> EpisodeResult:
        """The episode so far; a part still waiting (an env episode its caller stopped) is reported not picked."""
        cell = self.cell
        waiting = tuple(_not_picked(part, "the episode ended before its pick") for part in self.remaining)
        return EpisodeResult(tuple(self.picks) + waiting, time.perf_counter() - self._start,
                             float(self.world.data.time), self.looks, self.occupied_looks, cell.protective_stops,
                             cell.stopped_s, cell.min_human_clearance * 1e3)

    def close(self) -> None:
        if self.perception is not None:
            self.perception.close()

    def __enter__(self) -> Episode:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _wanted(world: World) -> tuple[list[str], dict[str, str | None]]:
    """The bodies to pick, in order, and the colour each is wanted in (None: any), from ``WorldConfig.pick``
    (every body in task order when it is empty). Which body a colour names is the simulator's truth, used
    to grade the pick; the robot goes by the colour it sees."""
    if not world.config.pick:
        return list(world.workpieces), dict.fromkeys(world.workpieces)
    bodies, colours = [], {}
    for entry in world.config.pick:
        colour, part = pick_target(entry, world.config.workpieces)
        left = [b for b in world.bodies_of(part) if b not in colours]
        match = [b for b in left if colour in (None, world.colour_name(b))]
        if not match:
            seen = ", ".join(f"{b} ({world.colour_name(b)})" for b in world.bodies_of(part))
            raise SimInputError(f"pick {entry!r}: no {part}{' in ' + colour if colour else ''} is left to pick; "
                                f"the table holds {seen}, and pick names each at most once")
        bodies.append(match[0])
        colours[match[0]] = colour
    return bodies, colours


def _not_picked(part: str, why: str) -> PickResult:
    return PickResult(part, "", False, 0.0, False, math.nan, math.nan, math.nan, math.nan, why, 0)


def run_episode(world: World, rng: np.random.Generator, poses: PoseSource | str = PoseSource.ORACLE,
                occluder: bool = False, recorder: Recorder | None = None,
                perception: PerceptionParams | None = None) -> EpisodeResult:
    """Reset the world to home and run the scripted policy (:class:`Episode`) to the end."""
    with Episode(world, rng, poses, occluder, recorder, perception=perception) as episode:
        return episode.run()
