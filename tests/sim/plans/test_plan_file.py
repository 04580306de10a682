"""Process plan files (sim/plans/plan_file.py): every key and term checked, with its line."""

from pathlib import Path

import pytest

from sim.errors import TaskFileError
from sim.plans import PlanObject, load_plan

REPO = Path(__file__).resolve().parents[3]
TASK = "workpieces:\n  - mesh: block.stl\n    count: 2\n    color: [red, blue]\n  - chassis\n"


@pytest.fixture
def folder(tmp_path):
    import trimesh

    trimesh.creation.box((0.04, 0.03, 0.02)).export(tmp_path / "block.stl")
    (tmp_path / "cell.yaml").write_text(TASK)
    return tmp_path


def _plan(folder, text: str):
    path = folder / "plan.yaml"
    path.write_text(text)
    return load_plan(path)


def test_a_plan_names_its_cell_goal_and_actions(folder):
    plan = _plan(folder, "task: cell.yaml\ngoal:\n  - in(red block, fixture)\n  - in(any chassis, fixture)\n"
                         "actions:\n  - pick(red block)\n  - place(red block, fixture)\n")
    assert [g.object for g in plan.goal] == [PlanObject("block", "red"), PlanObject("chassis")]
    assert [g.place for g in plan.goal] == ["fixture", "fixture"]
    assert plan.task.world.workpieces == ("block", "chassis")
    assert [(a.name, a.object.wanted, a.place) for a in plan.actions] == [
        ("pick", "red block", None), ("place", "red block", "fixture")]


@pytest.mark.parametrize(("text", "line", "words"), [
    ("task: cell.yaml\ngoal: [in(block, fixture)]\nsteps: 3\n", 3, "unknown key 'steps'"),
    ("task: cell.yaml\ngoal:\n  - on(block, fixture)\n", 3, "is not a goal"),
    ("task: cell.yaml\ngoal:\n  - in(gearbox, fixture)\n", 3, "object 'gearbox'"),
    ("task: cell.yaml\ngoal:\n  - in(crimson block, fixture)\n", 3, "'crimson' is not a colour"),
    ("task: cell.yaml\ngoal:\n  - in(block, shelf)\n", 3, "'shelf' is not a place"),
    ("task: cell.yaml\ngoal:\n  - in(block, fixture)\nactions:\n  - place(block)\n", 5, "is not an action"),
    ("task: cell.yaml\ngoal: in(block, fixture)\n", 2, "goal must be a list"),
    ("task: 3\ngoal: [in(block, fixture)]\n", 1, "task must be a task file"),
])
def test_each_bad_key_or_term_is_named_with_its_line(folder, text, line, words):
    with pytest.raises(TaskFileError) as caught:
        _plan(folder, text)
    message = str(caught.value)
    assert f"plan.yaml: line {line}: " in message and words in message, message


def test_a_plan_without_a_goal_or_its_task_is_refused(folder):
    with pytest.raises(TaskFileError, match="a plan needs goal:"):
        _plan(folder, "task: cell.yaml\n")
    with pytest.raises(TaskFileError, match="no such task file"):
        _plan(folder, "task: missing.yaml\ngoal: [in(block, fixture)]\n")


def test_the_shipped_plans_read():
    for name in ("kit", "red_hub", "sort", "busy_person"):
        plan = load_plan(REPO / "tasks" / "plans" / f"{name}.yaml")
        assert plan.goal
