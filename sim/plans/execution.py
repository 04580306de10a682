"""A process plan executed in the cell: objects bound by what the robot sees, the plan repaired when an
action fails.

Each plan object becomes an entry of ``WorldConfig.pick`` (``"red hub"``), so an :class:`sim.episode.Episode`
binds it to a recognised instance of its part, by the colour the look saw it in where the plan names
one. Which body that is stays simulator truth and only grades the action. The cell is looked at again
before every pick. A pick that fails with the part still on the table (not seen, not held) puts it back
among the objects to pick, and the rest of the goal is planned again from what is placed, up to
``max_replans`` times; a part carried to its place and left there unseated cannot be picked from there,
and the rest of the goal is planned without it.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from sim.episode import MAX_BLIND_LOOKS, Episode
from sim.errors import SimInputError, UnreachableGoalError, WorkspaceBlockedError
from sim.modes import PoseSource
from sim.plans.plan_file import ProcessPlan
from sim.plans.planning import check_actions, goal_places, solve
from sim.skills.judging import PickResult
from sim.world import build_world

MOVED_M = 0.01  # m a body the goal does not name may end from where it lay before it counts as moved


@dataclass(frozen=True)
class ActionOutcome:
    """One executed action: ``pick`` or ``place``, its object, its destination ("" for a pick) and what
    happened: ``grasped``, ``not grasped``, ``not recognised``, ``placed``, ``not placed``."""

    action: str
    object: str
    destination: str
    outcome: str


@dataclass(frozen=True)
class PlanResult:
    """A plan's run: whether the goal holds at the end (simulator truth), each action's outcome, how many
    times the plan was repaired, the wall time (s), the episode's picks (:class:`PickResult`), and the
    bodies the goal does not name that ended over ``MOVED_M`` from where they lay (truth: a twin of
    the wrong colour picked, or a neighbour pushed)."""

    goal_reached: bool
    actions: tuple[ActionOutcome, ...]
    replans: int
    wall_s: float
    picks: tuple[PickResult, ...]
    others_moved: tuple[str, ...] = ()

    def as_json(self) -> dict:
        return {"goal_reached": self.goal_reached, "actions": [dataclasses.asdict(a) for a in self.actions],
                "replans": self.replans, "wall_s": round(self.wall_s, 3)}


def run_plan(plan: ProcessPlan, rng: np.random.Generator, poses: PoseSource | str = PoseSource.RECOGNIZED,
             occluder: bool = True, max_replans: int | None = None) -> PlanResult:
    """Check, plan and execute ``plan`` in a cell built from ``rng`` (the only randomness).

    Raises:
        UnreachableGoalError: before the robot moves, when the goal cannot be reached in this cell.
    """
    start = time.perf_counter()
    objects = goal_places(plan)
    steps = check_actions(plan, objects) if plan.actions is not None else solve(objects, path=plan.path)
    config = dataclasses.replace(plan.task.world, pick=tuple(obj.wanted for obj, _ in objects.values()),
                                 occluder=occluder)
    world = build_world(config, rng)
    try:
        episode = Episode(world, rng, poses, occluder)
    except SimInputError as exc:  # a colour or a count the table does not hold
        raise UnreachableGoalError(f"{plan.path}: {exc}") from None
    with episode:
        bodies = dict(zip(objects, episode.remaining))
        outcomes, placed, lost, replans = [], set(), set(), 0
        limit = 2 * len(objects) if max_replans is None else max_replans
        pending = [s.object for s in steps if s.action == "pick"]
        while pending:
            # A planner's picks of different objects touch only their own object's facts and the hand, so
            # any order of them reaches the goal: take the first one this look sees. A person's order is kept.
            allowed = pending if plan.actions is None else pending[:1]
            name, result = _pick_and_place(episode, {bodies[n]: n for n in allowed})
            name = name or allowed[0]
            outcomes += _outcomes(name, objects[name][1], result)
            if result is not None and result.placed:
                placed.add(name)
                pending.remove(name)
                continue
            if result is not None and result.grasped:
                lost.add(name)  # carried to its place and left there unseated: the robot cannot pick it there
            elif replans < limit and bodies[name] not in episode.remaining:
                episode.remaining.insert(0, bodies[name])  # a pick tried takes it off; it is still on the table
            if replans >= limit:
                break
            replans += 1
            todo = {k: v for k, v in objects.items() if k not in lost}
            pending = [s.object for s in solve(todo, frozenset(placed), plan.path) if s.action == "pick"]
    reached = all(any(p.part == bodies[name] and p.placed for p in episode.picks) for name in objects)
    others = [b for b in world.workpieces if b not in bodies.values()]
    moved = tuple(b for b in others if np.linalg.norm(world.body_pose(b)[:3, 3]
                                                      - world.T_world_workpieces[b][:3, 3]) > MOVED_M)
    return PlanResult(reached, tuple(outcomes), replans, time.perf_counter() - start, tuple(episode.picks), moved)


def _pick_and_place(episode: Episode, wanted: dict[str, str]) -> tuple[str | None, PickResult | None]:
    """Look until one of ``wanted``'s objects (body -> object name, in the order to prefer) is seen where
    nobody reaches in, then pick and place it: (its name, the result). (None, None) when none was seen in
    ``MAX_BLIND_LOOKS`` looks in a row, or the workspace stayed blocked."""
    blind = looks = 0
    try:
        while blind < MAX_BLIND_LOOKS:
            look = episode.look()
            looks += 1
            if look.occupied:
                episode.wait()
                continue
            seen = episode.estimates(look)
            body = next((b for b in wanted if b in seen), None)
            if body is None:
                blind += 1
                episode.wait()
                continue
            if episode.cell.monitor is not None and episode.perception.occupied(episode.world.data,
                                                                               episode.cell.holding):
                episode.wait()
                continue
            estimate = seen[body]
            return wanted[body], episode.pick(body, estimate.T_world_part, looks=looks,
                                              alternatives=estimate.alternatives)
    except WorkspaceBlockedError:
        return None, None
    return None, None


def _outcomes(name: str, place: str, result: PickResult | None) -> list[ActionOutcome]:
    if result is None:
        return [ActionOutcome("pick", name, "", "not recognised")]
    pick = ActionOutcome("pick", name, "", "grasped" if result.grasped else "not grasped")
    if not result.grasped:
        return [pick]
    return [pick, ActionOutcome("place", name, place, "placed" if result.placed else "not placed")]
