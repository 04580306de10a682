"""Process plans executed in the cell (sim/plans/execution.py): objects bound by colour, failures repaired."""

import json
from pathlib import Path

import numpy as np
import pytest

import sim.plans.execution as execution
from sim.cli import main
from sim.errors import UnreachableGoalError
from sim.plans import load_plan, run_plan

REPO = Path(__file__).resolve().parents[3]


def _plan(tmp_path, goal: str, task: str = "workpieces: [chassis, transformer]\n"):
    (tmp_path / "cell.yaml").write_text(task)
    (tmp_path / "plan.yaml").write_text(f"task: cell.yaml\ngoal:\n{goal}")
    return load_plan(tmp_path / "plan.yaml")


def test_the_red_hub_is_placed_and_its_blue_twin_left_alone():
    plan = load_plan(REPO / "tasks" / "plans" / "red_hub.yaml")
    result = run_plan(plan, np.random.default_rng(3), poses="recognized", occluder=True)
    assert result.goal_reached, result.actions
    assert [(a.action, a.object, a.outcome) for a in result.actions][-2:] == [
        ("pick", "red_hub", "grasped"), ("place", "red_hub", "placed")]
    assert result.others_moved == ()  # neither the blue hub nor the transformer was touched


def test_a_colour_the_table_does_not_hold_is_refused_before_the_robot_moves(tmp_path):
    plan = _plan(tmp_path, "  - in(green chassis, fixture)\n")
    with pytest.raises(UnreachableGoalError, match="plan.yaml: pick 'green chassis': no chassis in green"):
        run_plan(plan, np.random.default_rng(0), poses="oracle", occluder=False)


def test_a_failed_action_is_repaired_by_planning_again(tmp_path, monkeypatch):
    real, calls = execution._pick_and_place, []

    def unseen_once(episode, wanted):
        calls.append(list(wanted))
        return (None, None) if len(calls) == 1 else real(episode, wanted)

    monkeypatch.setattr(execution, "_pick_and_place", unseen_once)
    plan = _plan(tmp_path, "  - in(chassis, fixture)\n  - in(transformer, fixture)\n")
    result = run_plan(plan, np.random.default_rng(0), poses="oracle", occluder=False)
    assert result.goal_reached and result.replans == 1
    outcomes = [(a.action, a.outcome) for a in result.actions]
    assert outcomes[0] == ("pick", "not recognised") and outcomes.count(("place", "placed")) == 2
    assert len(calls) == 3 and set(calls[1]) == set(calls[0])  # both objects still wanted after the failure


def test_plan_json_prints_one_line_of_the_contract(tmp_path, capsys):
    _plan(tmp_path, "  - in(transformer, fixture)\n")
    assert main(["plan", str(tmp_path / "plan.yaml"), "--poses", "oracle", "--occluder", "off", "--json",
                 "--pddl", str(tmp_path / "pddl")]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 1
    out = json.loads(lines[0])
    assert set(out) == {"goal_reached", "actions", "replans", "wall_s"} and out["goal_reached"] is True
    assert out["actions"][-1] == {"action": "place", "object": "transformer", "destination": "fixture",
                                  "outcome": "placed"}
    assert (tmp_path / "pddl" / "domain.pddl").is_file() and (tmp_path / "pddl" / "problem.pddl").is_file()
