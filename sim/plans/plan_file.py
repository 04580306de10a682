"""Process plan files (``tasks/plans/*.yaml``): the cell, the goal, and optionally a person's own actions.

::

    task: ../colour_pick.yaml        # the cell: its workpieces, their counts and colours (a task file)
    goal:                            # in(OBJECT, PLACE): an object is [any | a colour] and a part's name;
      - in(red hub, fixture)         #   a place is fixture (the one the cell builds for the part) or tote
      - in(transformer, fixture)
    actions:                         # optional: the order a person taught, checked against the goal
      - pick(transformer)
      - place(transformer, fixture)

Every key and term is checked before the world is built; a wrong one is named with its line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from sim.errors import SimInputError, TaskFileError
from sim.parts.source import PLACES
from sim.world.tasks import Task, load_task, read_lined_yaml

PLAN_KEYS = ("task", "goal", "actions")
_EXAMPLE = "see tasks/plans/kit.yaml"
_GOAL = re.compile(r"^in\(\s*([^,()]+?)\s*,\s*([A-Za-z_]+)\s*\)$")
_ACTION = re.compile(r"^(pick|place)\(\s*([^,()]+?)\s*(?:,\s*([A-Za-z_]+)\s*)?\)$")


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
    """A parsed plan file: its path, the cell's task, the goal, and the person's actions (None: plan them)."""

    path: Path
    task: Task
    goal: tuple[Goal, ...]
    actions: tuple[Action, ...] | None = None


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
    goal = tuple(_goal(path, text, line, task) for text, line in _items(path, spec, "goal"))
    actions = None
    if "actions" in spec:
        actions = tuple(_action(path, text, line, task) for text, line in _items(path, spec, "actions"))
    return ProcessPlan(path, task, goal, actions)


def _items(path: Path, spec, key: str):
    items = spec[key]
    if not isinstance(items, list) or not items or not all(isinstance(i, str) for i in items):
        raise TaskFileError(path, f"line {spec.lines[key]}: {key} must be a list of terms, such as "
                            f"{'in(red hub, fixture)' if key == 'goal' else 'pick(transformer)'}", _EXAMPLE)
    return zip(items, items.lines)


def _goal(path: Path, text: str, line: int, task: Task) -> Goal:
    match = _GOAL.match(text.strip())
    if match is None:
        raise TaskFileError(path, f"line {line}: {text!r} is not a goal", "write in(OBJECT, PLACE), such as "
                            "in(red hub, fixture) or in(any idler, tote)")
    return Goal(_object(path, match[1], line, task), _place(path, match[2], line))


def _action(path: Path, text: str, line: int, task: Task) -> Action:
    match = _ACTION.match(text.strip())
    if match is None or (match[1] == "place") != (match[3] is not None):
        raise TaskFileError(path, f"line {line}: {text!r} is not an action", "write pick(OBJECT) or "
                            "place(OBJECT, PLACE)")
    place = None if match[3] is None else _place(path, match[3], line)
    return Action(match[1], _object(path, match[2], line, task), place)


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


def _place(path: Path, text: str, line: int) -> str:
    if text not in PLACES:
        raise TaskFileError(path, f"line {line}: {text!r} is not a place", f"places are {', '.join(PLACES)}")
    return text
