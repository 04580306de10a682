"""The cell's STRIPS domain in unified-planning, solved by an engine it installs (pyperplan), and as PDDL.

Types ``part`` (a plan's symbolic objects) and ``location``; fluents ``on_table(p)``, ``holding(p)``,
``hand_empty``, ``in(p, l)``, ``free(l)``, and the static ``fits(p, l)``; actions ``pick(p)`` and
``place(p, l)``. Each object has a place of its own: the fixture the cell builds for its part, a fixture
the plan names (which holds one part: a second object wanted there finds it occupied), or its slot in
the tote, as the task places the part; a goal that sends it elsewhere cannot be reached.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from sim.errors import UnreachableGoalError
from sim.plans.plan_file import Goal, PlanObject, ProcessPlan

ENGINE = "pyperplan"


@dataclass(frozen=True)
class Step:
    """One action of a plan: ``pick(object)`` (place None) or ``place(object, place)``, place being
    ``"fixture"``, ``"tote"`` or a fixture the plan names."""

    action: str
    object: str
    place: str | None = None


def goal_places(plan: ProcessPlan) -> dict[str, tuple[PlanObject, str]]:
    """Object name -> (object, the place the goal wants it in), refusing a goal at odds with itself or with
    the cell: a part sent where the cell does not put it, or two objects wanted in one named fixture."""
    from sim.world.parts import instance_names, places

    cell = {instance_names(plan.task.world)[body]: where for body, where in places(plan.task.world).items()}
    wanted: dict[str, tuple[PlanObject, str]] = {}
    for goal in plan.goal:
        name, term = _name(goal, wanted), f"in({goal.object.wanted}, {goal.place})"
        if cell.get(goal.object.part) != plan.kind(goal.place):
            raise UnreachableGoalError(f"{plan.path}: {term} cannot be reached: the "
                                       f"cell puts {goal.object.part} in {_article(cell[goal.object.part])}")
        held = next((obj for obj, place in wanted.values() if place == goal.place), None)
        if held is not None and plan.destination(goal.place) is not None:
            raise UnreachableGoalError(f"{plan.path}: {term} cannot be reached: {goal.place} holds one part, and "
                                       f"the goal has already put {held.wanted} there")
        wanted[name] = (goal.object, goal.place)
    return wanted


def _name(goal: Goal, wanted: dict) -> str:
    """The goal object's name in the problem: ``red_hub``; a second hub of the same description ``hub_2``."""
    base, k = goal.object.name, 2
    name = base
    while name in wanted:
        name, k = f"{base}_{k}", k + 1
    return name


def _article(place: str) -> str:
    return "its fixture" if place == "fixture" else "the tote"


def problem(objects: dict[str, tuple[PlanObject, str]], placed: frozenset[str] = frozenset()):
    """The unified-planning problem of ``objects`` (name -> (object, place)) with ``placed`` ones in place."""
    from unified_planning.shortcuts import BoolType, Fluent, InstantaneousAction, Object, Problem, UserType

    part, place = UserType("part"), UserType("location")
    on_table, holding = Fluent("on_table", BoolType(), p=part), Fluent("holding", BoolType(), p=part)
    inside, fits = Fluent("in", BoolType(), p=part, l=place), Fluent("fits", BoolType(), p=part, l=place)
    free, hand_empty = Fluent("free", BoolType(), l=place), Fluent("hand_empty", BoolType())
    pick = InstantaneousAction("pick", p=part)
    p = pick.parameter("p")
    pick.add_precondition(on_table(p))
    pick.add_precondition(hand_empty())
    for fluent, value in ((on_table(p), False), (holding(p), True), (hand_empty(), False)):
        pick.add_effect(fluent, value)
    put = InstantaneousAction("place", p=part, l=place)
    p, at = put.parameters
    for condition in (holding(p), free(at), fits(p, at)):
        put.add_precondition(condition)
    for fluent, value in ((holding(p), False), (inside(p, at), True), (free(at), False), (hand_empty(), True)):
        put.add_effect(fluent, value)
    cell = Problem("cell")
    for fluent in (on_table, holding, inside, fits, free, hand_empty):
        cell.add_fluent(fluent, default_initial_value=False)
    cell.add_actions([pick, put])
    cell.set_initial_value(hand_empty(), True)
    for name, (_, where) in objects.items():
        thing, spot = Object(name, part), Object(_place_name(name, where), place)
        cell.add_objects([thing, spot])
        cell.set_initial_value(fits(thing, spot), True)
        cell.set_initial_value(inside(thing, spot) if name in placed else on_table(thing), True)
        cell.set_initial_value(free(spot), name not in placed)
        cell.add_goal(inside(thing, spot))
    return cell


def _place_name(name: str, where: str) -> str:
    """The place's object: the part's own fixture or tote slot, or a named fixture (one for every object
    wanted there)."""
    return {"fixture": f"{name}_fixture", "tote": f"{name}_tote_slot"}.get(where, where)


def solve(objects: dict[str, tuple[PlanObject, str]], placed: frozenset[str] = frozenset(),
          path: Path | None = None) -> tuple[Step, ...]:
    """A plan that puts every object in its place, from the planner; UnreachableGoalError if there is none."""
    from unified_planning.shortcuts import OneshotPlanner, get_environment

    get_environment().credits_stream = None  # the engines' credits would print on every solve
    with OneshotPlanner(name=ENGINE) as planner:
        result = planner.solve(problem(objects, placed))
    if result.plan is None:
        raise UnreachableGoalError(f"{path or 'the plan'}: the planner ({ENGINE}) found no plan: {result.status.name}")
    return _in_goal_order(tuple(_step(a, objects) for a in result.plan.actions), objects)


def _in_goal_order(steps: tuple[Step, ...], objects: dict) -> tuple[Step, ...]:
    """The plan's steps with each object's pick and place kept together, objects in the goal's order.

    The engine orders interchangeable objects by Python's string hashing, which changes from process to
    process, so a seed would not reproduce a run. In this domain an object's steps touch only its own facts,
    its own place and the hand, so any order of whole objects is as valid as the engine's."""
    rank = {name: k for k, name in enumerate(objects)}
    return tuple(sorted(steps, key=lambda s: (rank[s.object], s.action != "pick")))


def _step(action, objects) -> Step:
    name = str(action.actual_parameters[0])
    return Step(action.action.name, name, objects[name][1] if action.action.name == "place" else None)


def check_actions(plan: ProcessPlan, objects: dict[str, tuple[PlanObject, str]]) -> tuple[Step, ...]:
    """The person's actions as steps, once the plan validator finds that they reach the goal."""
    from unified_planning.plans import ActionInstance, SequentialPlan
    from unified_planning.shortcuts import PlanValidator, get_environment

    get_environment().credits_stream = None
    cell = problem(objects)
    by_part = {}
    for name, (obj, _) in objects.items():
        by_part.setdefault(obj, []).append(name)
    steps, instances = [], []
    for act in plan.actions:
        names = by_part.get(act.object)
        if not names:
            raise UnreachableGoalError(f"{plan.path}: the action {act.name}({act.object.wanted}) is about an object "
                                       "the goal does not name")
        name = names[0]
        steps.append(Step(act.name, name, act.place))
        args = [cell.object(name)]
        if act.name == "place":
            args.append(cell.object(_place_name(name, act.place)) if act.place == objects[name][1] else None)
            if args[-1] is None:
                raise UnreachableGoalError(f"{plan.path}: place({act.object.wanted}, {act.place}) puts it where the "
                                           f"goal does not want it ({objects[name][1]})")
            by_part[act.object] = names[1:] + names[:1]  # the next place of this description is the next object
        instances.append(ActionInstance(cell.action(act.name), args))
    with PlanValidator(problem_kind=cell.kind) as validator:
        verdict = validator.validate(cell, SequentialPlan(instances))
    if not verdict.status.name == "VALID":
        reason = getattr(verdict, "reason", None) or verdict.status.name
        raise UnreachableGoalError(f"{plan.path}: the person's actions do not reach the goal ({reason})")
    return tuple(steps)


def write_pddl(objects: dict[str, tuple[PlanObject, str]], out: Path) -> tuple[Path, Path]:
    """Write the domain and problem as ``out/domain.pddl`` and ``out/problem.pddl``."""
    from unified_planning.io import PDDLWriter

    out.mkdir(parents=True, exist_ok=True)
    writer = PDDLWriter(problem(objects))
    domain, task = out / "domain.pddl", out / "problem.pddl"
    writer.write_domain(str(domain))
    writer.write_problem(str(task))
    return domain, task
