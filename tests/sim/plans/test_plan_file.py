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
    ("task: cell.yaml\ndestinations: [fixture_a]\ngoal: [in(block, fixture)]\n", 2, "destinations must map"),
    ("task: cell.yaml\ndestinations:\n  fixture: block\ngoal: [in(block, fixture)]\n", 3,
     "'fixture' cannot name a destination"),
    ("task: cell.yaml\ndestinations:\n  fixture_a: gearbox\ngoal: [in(block, fixture)]\n", 3,
     "'gearbox' is not a part of the task"),
    ("task: cell.yaml\ndestinations:\n  a: block\n  b: block\n  c: block\ngoal: [in(block, a)]\n", 5,
     "the cell builds only 2 block fixture(s)"),
    ("task: cell.yaml\ndestinations:\n  fixture_a: block\ngoal:\n  - in(chassis, fixture_a)\n", 5,
     "fixture_a is a fixture for block, not for chassis"),
    ("task: cell.yaml\ndestinations:\n  fixture_a: block\ngoal:\n  - in(red block, fixture)\n", 5,
     "the plan names the block fixtures"),
    ("task: cell.yaml\ndestinations:\n  fixture_a: block\ngoal:\n  - in(block, fixture_a)\nactions:\n"
     "  - pick(block)\n  - place(block, fixture_z)\n", 8, "'fixture_z' is not a place"),
])
def test_each_bad_key_or_term_is_named_with_its_line(folder, text, line, words):
    with pytest.raises(TaskFileError) as caught:
        _plan(folder, text)
    message = str(caught.value)
    assert f"plan.yaml: line {line}: " in message and words in message, message


def test_a_plan_names_fixtures_of_parts_the_cell_puts_in_fixtures(folder):
    plan = _plan(folder, "task: cell.yaml\ndestinations:\n  fixture_a: block\n  fixture_b: chassis\ngoal:\n"
                         "  - in(red block, fixture_a)\n  - in(chassis, fixture_b)\n")
    assert [(d.name, d.part) for d in plan.destinations] == [("fixture_a", "block"), ("fixture_b", "chassis")]
    assert [g.place for g in plan.goal] == ["fixture_a", "fixture_b"]
    assert (plan.kind("fixture_a"), plan.kind("tote"), plan.destination("fixture")) == ("fixture", "tote", None)
    (folder / "cell.yaml").write_text(TASK.replace("color: [red, blue]", "color: [red, blue]\n    place: tote"))
    with pytest.raises(TaskFileError, match="line 3: fixture_a: the cell puts block in the tote"):
        _plan(folder, "task: cell.yaml\ndestinations:\n  fixture_a: block\ngoal: [in(block, tote)]\n")


def test_a_plan_without_a_goal_or_its_task_is_refused(folder):
    with pytest.raises(TaskFileError, match="a plan needs goal:"):
        _plan(folder, "task: cell.yaml\n")
    with pytest.raises(TaskFileError, match="no such task file"):
        _plan(folder, "task: missing.yaml\ngoal: [in(block, fixture)]\n")


def test_the_shipped_plans_read():
    for name in ("kit", "red_hub", "sort", "busy_person"):
        plan = load_plan(REPO / "tasks" / "plans" / f"{name}.yaml")
        assert plan.goal
    assert load_plan(REPO / "tasks" / "plans" / "kit.yaml").goal[1].place == "fixture_a"  # as the paper names it
