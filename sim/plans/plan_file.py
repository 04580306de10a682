"""Process plan files (``tasks/plans/*.yaml``): the cell, the goal, and optionally a person's own actions.

::

    task: ../colour_pick.yaml        # the cell: its workpieces, their counts and colours (a task file)
    destinations:                    # optional: names for the cell's fixtures, each one for a part
      fixture_b: hub                 #   one of the hub's fixtures (alike: one per instance), holding one part
    goal:                            # in(OBJECT, PLACE): an object is [any | a colour] and a part's name;
      - in(red hub, fixture_b)       #   a place is a named destination, fixture (the part's own) or tote
      - in(transformer, fixture)
    actions:                         # optional: the order a person taught, checked against the goal
      - pick(transformer)
      - place(transformer, fixture)

Every key and term is checked before the world is built; a wrong one is named with its line.

A part's instances each get a fixture of their own, all alike. A named fixture is one of them: the one of
the instance its object is bound to when the robot sees it. Once a plan names fixtures for a part, that
part's places are named ones only, so no fixture is wanted under two names.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from sim.errors import SimInputError, TaskFileError
from sim.parts.source import PLACES
from sim.world.tasks import Task, load_task, read_lined_yaml

PLAN_KEYS = ("task", "destinations", "goal", "actions")
_EXAMPLE = "see tasks/plans/kit.yaml"
_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
_GOAL = re.compile(rf"^in\(\s*([^,()]+?)\s*,\s*({_NAME})\s*\)$")
_ACTION = re.compile(rf"^(pick|place)\(\s*([^,()]+?)\s*(?:,\s*({_NAME})\s*)?\)$")


@dataclass(frozen=True)
class PlanObject:
    """A symbolic object of a plan: an instance of ``part``, in ``colour`` when one is given."""

    part: str
    colour: str | None = None

    @property
    def name(self) -> str:
        """Its name in the planning problem and the reports: ``red_hub``, ``hub``."""
        return f"{self.colour}_{self.part}" if self.colour else self.part

    @property
    def wanted(self) -> str:
        """As ``WorldConfig.pick`` names it: ``"red hub"``."""
        return f"{self.colour} {self.part}" if self.colour else self.part


@dataclass(frozen=True)
class Destination:
    """A fixture a plan names (``fixture_a``): one of the cell's fixtures for ``part``, holding one part."""

    name: str
    part: str


@dataclass(frozen=True)
class Goal:
    """``in(object, place)``."""

    object: PlanObject
    place: str


@dataclass(frozen=True)
class Action:
    """A person's step: ``pick(object)`` (place None) or ``place(object, place)``."""

    name: str
    object: PlanObject
    place: str | None = None


@dataclass(frozen=True)
class ProcessPlan:
    """A parsed plan file: its path, the cell's task, the goal, the person's actions (None: plan them), and
    the fixtures it names."""

    path: Path
    task: Task
    goal: tuple[Goal, ...]
    actions: tuple[Action, ...] | None = None
    destinations: tuple[Destination, ...] = ()

    def destination(self, place: str) -> Destination | None:
        """The named fixture ``place``; None for ``"fixture"`` and ``"tote"``."""
        return next((d for d in self.destinations if d.name == place), None)

    def kind(self, place: str) -> str:
        """``"fixture"`` or ``"tote"``: what the place is."""
        return "fixture" if self.destination(place) is not None else place


def load_plan(path) -> ProcessPlan:
    """Read a plan file; a bad key, term, object or place raises TaskFileError naming its line and the fix."""
    path = Path(path)
    spec = read_lined_yaml(path, "plan", _EXAMPLE)
    if not isinstance(spec, dict):
        raise TaskFileError(path, "a plan must be a mapping", f"give the keys {', '.join(PLAN_KEYS)}")
    for key in spec:
        if key not in PLAN_KEYS:
            raise TaskFileError(path, f"line {spec.lines[key]}: unknown key {key!r}",
                                f"valid keys are {', '.join(PLAN_KEYS)}")
    for key in ("task", "goal"):
        if key not in spec:
            raise TaskFileError(path, f"a plan needs {key}:", _EXAMPLE)
    if not isinstance(spec["task"], str):
        raise TaskFileError(path, f"line {spec.lines['task']}: task must be a task file's path", _EXAMPLE)
    task = load_task((path.parent / spec["task"]).resolve())
    named = _destinations(path, spec, task) if "destinations" in spec else ()
    goal = tuple(_goal(path, text, line, task, named) for text, line in _items(path, spec, "goal"))
    actions = None
    if "actions" in spec:
        actions = tuple(_action(path, text, line, task, named) for text, line in _items(path, spec, "actions"))
    return ProcessPlan(path, task, goal, actions, named)


def _destinations(path: Path, spec, task: Task) -> tuple[Destination, ...]:
    """The fixtures the plan names, each for a part the cell puts in fixtures, no more of a part than it
    has instances."""
    from sim.world.parts import instance_names, places

    given = spec["destinations"]
    if not isinstance(given, dict) or not given:
        raise TaskFileError(path, f"line {spec.lines['destinations']}: destinations must map names to parts, "
                            "such as {fixture_a: transformer}", _EXAMPLE)
    types, where = instance_names(task.world), places(task.world)
    out = []
    for name, part in given.items():
        line = given.lines[name]
        if not isinstance(name, str) or not re.fullmatch(_NAME, name) or name in PLACES:
            raise TaskFileError(path, f"line {line}: {name!r} cannot name a destination", "use a word of letters, "
                                f"digits and _ other than {' or '.join(PLACES)}, such as fixture_a")
        if part not in task.world.workpieces:
            raise TaskFileError(path, f"line {line}: {name}: {part!r} is not a part of the task",
                                f"name one of {', '.join(task.world.workpieces)}")
        if "fixture" not in (where[b] for b, t in types.items() if t == part):
            raise TaskFileError(path, f"line {line}: {name}: the cell puts {part} in the tote, not in a fixture",
                                "send it to tote, or rest it upright in the task")
        instances = sum(t == part for t in types.values())
        if sum(d.part == part for d in out) >= instances:
            raise TaskFileError(path, f"line {line}: {name}: the cell builds only {instances} {part} fixture(s)",
                                f"name no more {part} fixtures than the task has {part}s")
        out.append(Destination(name, part))
    return tuple(out)


def _items(path: Path, spec, key: str):
    items = spec[key]
    if not isinstance(items, list) or not items or not all(isinstance(i, str) for i in items):
        raise TaskFileError(path, f"line {spec.lines[key]}: {key} must be a list of terms, such as "
                            f"{'in(red hub, fixture)' if key == 'goal' else 'pick(transformer)'}", _EXAMPLE)
    return zip(items, items.lines)


def _goal(path: Path, text: str, line: int, task: Task, named: tuple[Destination, ...]) -> Goal:
    match = _GOAL.match(text.strip())
    if match is None:
        raise TaskFileError(path, f"line {line}: {text!r} is not a goal", "write in(OBJECT, PLACE), such as "
                            "in(red hub, fixture) or in(any idler, tote)")
    obj = _object(path, match[1], line, task)
    return Goal(obj, _place(path, match[2], line, obj, named))


def _action(path: Path, text: str, line: int, task: Task, named: tuple[Destination, ...]) -> Action:
    match = _ACTION.match(text.strip())
    if match is None or (match[1] == "place") != (match[3] is not None):
        raise TaskFileError(path, f"line {line}: {text!r} is not an action", "write pick(OBJECT) or "
                            "place(OBJECT, PLACE)")
    obj = _object(path, match[2], line, task)
    return Action(match[1], obj, None if match[3] is None else _place(path, match[3], line, obj, named))


def _object(path: Path, text: str, line: int, task: Task) -> PlanObject:
    from sim.world.config import pick_target

    words = text.split()
    if words and words[0] == "any":
        words = words[1:]
    try:
        colour, part = pick_target(" ".join(words), task.world.workpieces)
    except SimInputError as exc:
        raise TaskFileError(path, f"line {line}: object {text!r}: {str(exc).split(': ', 1)[1]}") from None
    return PlanObject(part, colour)


def named_place_problem(named: tuple[Destination, ...], part: str, place: str) -> tuple[str, str] | None:
    """(problem, fix) when the plan's named fixtures rule out ``part`` going to ``place``: a named fixture made
    for another part, or ``"fixture"`` for a part whose fixtures the plan names; else None."""
    mine = [d.name for d in named if d.part == part]
    other = next((d.part for d in named if d.name == place and d.part != part), None)
    if other is not None:
        return (f"{place} is a fixture for {other}, not for {part}",
                f"send {part} to {' or '.join(mine) or 'fixture or tote'}")
    if place == "fixture" and mine:
        return f"the plan names the {part} fixtures", f"say which: {' or '.join(mine)}"
    return None


def _place(path: Path, text: str, line: int, obj: PlanObject, named: tuple[Destination, ...]) -> str:
    names = [d.name for d in named]
    if text not in PLACES and text not in names:
        raise TaskFileError(path, f"line {line}: {text!r} is not a place", f"places are {', '.join((*names, *PLACES))}")
    problem = named_place_problem(named, obj.part, text)
    if problem is not None:
        raise TaskFileError(path, f"line {line}: {problem[0]}", problem[1])
    return text
