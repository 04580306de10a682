"""The cell's STRIPS domain in unified-planning (sim/plans/planning.py): plans, PDDL, and goals refused."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from sim.errors import UnreachableGoalError
from sim.plans import Step, goal_places, load_plan, solve, write_pddl
from sim.plans.planning import check_actions

REPO = Path(__file__).resolve().parents[3]


def _plan(tmp_path, goal: str, actions: str = "", task: str = "workpieces: [chassis, transformer]\n",
          destinations: str = ""):
    (tmp_path / "cell.yaml").write_text(task)
    path = tmp_path / "plan.yaml"
    named = f"destinations:\n{destinations}" if destinations else ""
    path.write_text(f"task: cell.yaml\n{named}goal:\n{goal}" + (f"actions:\n{actions}" if actions else ""))
    return load_plan(path)


def test_the_planner_puts_every_object_in_its_place(tmp_path):
    plan = _plan(tmp_path, "  - in(chassis, fixture)\n  - in(transformer, fixture)\n")
    steps = solve(goal_places(plan))
    assert steps == (Step("pick", "chassis"), Step("place", "chassis", "fixture"),
                     Step("pick", "transformer"), Step("place", "transformer", "fixture"))


_ORDER = """
import sys
from sim.plans import goal_places, load_plan, solve
print([s.object for s in solve(goal_places(load_plan(sys.argv[1]))) if s.action == "pick"])
"""


def test_the_plans_order_does_not_change_with_pythons_string_hashing(tmp_path):
    """The engine alone orders interchangeable objects by string hashes, which differ from process to
    process (these two hash seeds give it different orders); the plan keeps the goal's order."""
    _plan(tmp_path, "  - in(circuit_board, fixture)\n  - in(chassis, fixture)\n  - in(transformer, fixture)\n",
          task="workpieces: [chassis, transformer, circuit_board]\n")
    orders = {subprocess.run([sys.executable, "-c", _ORDER, str(tmp_path / "plan.yaml")], check=True, text=True,
                             capture_output=True, cwd=REPO, env={**os.environ, "PYTHONHASHSEED": str(seed)}
                             ).stdout.strip().splitlines()[-1] for seed in (0, 1)}
    assert orders == {"['circuit_board', 'chassis', 'transformer']"}


def test_a_replan_leaves_out_what_is_placed(tmp_path):
    plan = _plan(tmp_path, "  - in(chassis, fixture)\n  - in(transformer, fixture)\n")
    steps = solve(goal_places(plan), frozenset({"chassis"}))
    assert steps == (Step("pick", "transformer"), Step("place", "transformer", "fixture"))


def test_a_part_sent_where_the_cell_cannot_put_it_is_refused(tmp_path):
    plan = _plan(tmp_path, "  - in(chassis, tote)\n")
    with pytest.raises(UnreachableGoalError, match="in\\(chassis, tote\\) cannot be reached: the cell puts "
                                                   "chassis in its fixture"):
        goal_places(plan)


def test_the_persons_actions_are_taken_when_they_reach_the_goal(tmp_path):
    plan = _plan(tmp_path, "  - in(chassis, fixture)\n",
                 "  - pick(chassis)\n  - place(chassis, fixture)\n")
    assert check_actions(plan, goal_places(plan)) == (Step("pick", "chassis"), Step("place", "chassis", "fixture"))


def test_actions_that_fall_short_of_the_goal_are_refused(tmp_path):
    plan = _plan(tmp_path, "  - in(chassis, fixture)\n  - in(transformer, fixture)\n",
                 "  - pick(chassis)\n  - place(chassis, fixture)\n")
    with pytest.raises(UnreachableGoalError, match="the person's actions do not reach the goal"):
        check_actions(plan, goal_places(plan))


def test_actions_out_of_order_are_refused(tmp_path):
    plan = _plan(tmp_path, "  - in(chassis, fixture)\n", "  - place(chassis, fixture)\n  - pick(chassis)\n")
    with pytest.raises(UnreachableGoalError, match="do not reach the goal"):
        check_actions(plan, goal_places(plan))


def test_the_domain_and_problem_are_written_as_pddl(tmp_path):
    plan = load_plan(REPO / "tasks" / "plans" / "red_hub.yaml")
    domain, problem = write_pddl(goal_places(plan), tmp_path / "pddl")
    assert "(:action pick" in domain.read_text() and "(:action place" in domain.read_text()
    text = problem.read_text()
    assert "red_hub - part" in text and "fixture_b - location" in text and "(in red_hub fixture_b)" in text


def test_named_fixtures_are_places_of_their_own(tmp_path):
    plan = _plan(tmp_path, "  - in(transformer, fixture_a)\n  - in(chassis, fixture_b)\n",
                 destinations="  fixture_a: transformer\n  fixture_b: chassis\n")
    assert solve(goal_places(plan)) == (Step("pick", "transformer"), Step("place", "transformer", "fixture_a"),
                                        Step("pick", "chassis"), Step("place", "chassis", "fixture_b"))


def test_a_named_fixture_wanted_for_two_parts_is_refused_as_occupied(tmp_path):
    import trimesh

    trimesh.creation.box((0.04, 0.03, 0.02)).export(tmp_path / "block.stl")
    plan = _plan(tmp_path, "  - in(red block, fixture_b)\n  - in(blue block, fixture_b)\n",
                 task="workpieces:\n  - mesh: block.stl\n    count: 2\n    color: [red, blue]\n",
                 destinations="  fixture_b: block\n  fixture_c: block\n")
    with pytest.raises(UnreachableGoalError, match="in\\(blue block, fixture_b\\) cannot be reached: fixture_b "
                                                   "holds one part, and the goal has already put red block there"):
        goal_places(plan)


def test_a_person_placing_in_a_named_fixture_is_checked_like_any_place(tmp_path):
    plan = _plan(tmp_path, "  - in(chassis, fixture_b)\n", "  - pick(chassis)\n  - place(chassis, fixture_b)\n",
                 destinations="  fixture_b: chassis\n")
    assert check_actions(plan, goal_places(plan))[-1] == Step("place", "chassis", "fixture_b")
