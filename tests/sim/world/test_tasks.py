"""Task files naming catalog parts and users' meshes (sim/world/tasks.py): every key checked, with its line."""

from pathlib import Path

import numpy as np
import pytest
import trimesh

from sim.errors import TaskFileError
from sim.parts.source import MeshPart
from sim.world.tasks import MESH_KEYS, TASK_KEYS, load_task

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture
def folder(tmp_path):
    box = trimesh.creation.box((40.0, 30.0, 20.0))
    (tmp_path / "parts").mkdir()
    box.export(tmp_path / "parts" / "block.stl")
    return tmp_path


def _task(folder, text: str):
    path = folder / "task.yaml"
    path.write_text(text)
    return load_task(path)


def test_a_task_names_catalog_parts_and_meshes(folder):
    task = _task(folder, "workpieces:\n  - chassis\n  - mesh: parts/block.stl\n    units: mm\n"
                         "    color: [0.8, 0.2, 0.2]\nmin_gap: 0.0\n")
    assert task.world.workpieces == ("chassis", "block")
    (part,) = task.world.mesh_parts
    assert part == MeshPart((folder / "parts" / "block.stl").resolve(), units="mm", color=(0.8, 0.2, 0.2))
    assert part.scale == 1e-3 and task.world.gap == 0.0


def test_a_name_replaces_the_file_stem(folder):
    task = _task(folder, "workpieces:\n  - mesh: parts/block.stl\n    name: spacer\n")
    assert task.world.workpieces == ("spacer",) and task.world.mesh_parts[0].name == "spacer"


@pytest.mark.parametrize(("text", "line", "words"), [
    ("workpieces: [chassis]\nspeed: 3\n", 2, "unknown key 'speed'"),
    ("workpieces:\n  - chassis\n  - gearbox\n", 3, "unknown workpiece 'gearbox'"),
    ("workpieces:\n  - mesh: parts/block.stl\n    colour: [1, 0, 0]\n", 3, "unknown key 'colour'"),
    ("workpieces:\n  - mesh: parts/block.stl\n    units: inch\n", 3, "units must be one of m, cm, mm, in"),
    ("workpieces:\n  - mesh: parts/block.stl\n    color: [1, 0]\n", 3, "color must be 3 numbers"),
    ("workpieces:\n  - mesh: parts/block.stl\n    color: crimson\n", 3, "'crimson' is not a palette name"),
    ("workpieces:\n  - mesh: parts/block.stl\n    count: 2\n    color: [red]\n", 4, "1 colours for count 2"),
    ("workpieces: [chassis]\npick: [gearbox]\n", 2, "pick 'gearbox': name a part on the table"),
    ("workpieces: [chassis]\npick: [crimson chassis]\n", 2, "'crimson' is not a colour"),
    ("workpieces: [chassis]\npick: 3\n", 2, "pick must be a list"),
    ("workpieces:\n  - mesh: parts/block.stl\n    count: 0\n", 3, "count must be a whole number"),
    ("workpieces:\n  - mesh: parts/block.stl\n    density: -1\n", 3, "density must be a positive number"),
    ("workpieces:\n  - mesh: parts/block.stl\n    place: shelf\n", 3, "place must be one of fixture, tote"),
    ("workpieces:\n  - mesh: parts/block.stl\n    name: 2nd part\n", 3, "name must start with a letter"),
    ("workpieces:\n  - mesh: parts/missing.stl\n", 2, "no mesh file"),
    ("workpieces:\n  - units: mm\n", 2, "needs mesh: FILE"),
    ("workpieces:\n  - mesh: parts/block.stl\n    name: chassis\n", 2, "is a catalog part's"),
    ("workpieces: [chassis]\nresting: sideways\n", 2, "resting must be one of upright, any"),
    ("workpieces: [chassis]\nmin_gap: wide\n", 2, "min_gap must be a number"),
    ("workpieces: [chassis]\nreach_gap: [2, 1]\n", 2, "reach_gap must be [min, max] seconds"),
    ("workpieces: [chassis]\nreach_gap: 1\n", 2, "reach_gap must be [min, max] seconds"),
])
def test_each_bad_key_is_named_with_its_line(folder, text, line, words):
    with pytest.raises(TaskFileError) as caught:
        _task(folder, text)
    message = str(caught.value)
    assert f"task.yaml: line {line}: " in message and words in message, message


def test_instances_take_a_colour_each_and_pick_names_one_by_colour(folder):
    task = _task(folder, "workpieces:\n  - mesh: parts/block.stl\n    count: 2\n    color: [red, [0.1, 0.2, 0.9]]\n"
                         "  - chassis\npick: [red block, chassis]\n")
    (part,) = task.world.mesh_parts
    assert part.instance_colors == ((0.8, 0.1, 0.1), (0.1, 0.2, 0.9)) and part.color == (0.8, 0.1, 0.1)
    assert task.world.pick == ("red block", "chassis")


def test_the_error_lists_the_valid_keys(folder):
    with pytest.raises(TaskFileError, match=", ".join(TASK_KEYS)):
        _task(folder, "workpieces: [chassis]\ncamera: 3\n")
    with pytest.raises(TaskFileError, match=", ".join(MESH_KEYS)):
        _task(folder, "workpieces:\n  - mesh: parts/block.stl\n    unit: mm\n")


def test_a_negative_gap_and_a_part_twice_are_refused(folder):
    with pytest.raises(TaskFileError, match="gap"):
        _task(folder, "workpieces: [chassis]\nmin_gap: -0.01\n")
    with pytest.raises(TaskFileError, match="each once"):
        _task(folder, "workpieces:\n  - mesh: parts/block.stl\n  - mesh: parts/block.stl\n")


def test_the_shipped_colour_pick_task_reads():
    task = load_task(REPO / "tasks" / "colour_pick.yaml")
    assert task.world.pick == ("red hub",) and task.world.mesh_parts[0].count == 2


def test_the_busy_person_task_makes_the_person_reach_more_often():
    busy = load_task(REPO / "tasks" / "busy_person.yaml").world
    assert busy.reach_gap_s == (0.5, 2.0)
    assert busy.reach_gap_s[1] <= load_task(REPO / "tasks" / "demo.yaml").world.reach_gap_s[0]


def test_the_shipped_demo_task_still_reads():
    task = load_task(REPO / "tasks" / "demo.yaml")
    assert task.world.workpieces == ("u_channel", "chassis", "transformer", "flanged_hub")
    assert task.world.mesh_parts == () and np.isclose(task.world.gap, 0.02)
