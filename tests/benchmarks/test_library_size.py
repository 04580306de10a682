"""The library-size benchmark's choice of libraries and its summary (benchmarks/library_size.py) on names and
hand-made results; the benchmark itself needs ../shared (or a folder of meshes) and runs as a script."""

from __future__ import annotations

import sys

import pytest
from paths import BENCHMARKS

sys.path.insert(0, str(BENCHMARKS))
import generalization_parts as parts  # noqa: E402
import library_size  # noqa: E402
import library_size_report  # noqa: E402


def test_the_libraries_grow_from_the_shown_parts_to_every_part():
    names = {f"part-{k:02d}": None for k in range(25)}
    shown, libraries = library_size.libraries(names)
    assert len(shown) == library_size.SHOWN
    assert [len(names) for names in libraries] == [10, 13, 25]  # the dev half takes the odd one of 25
    assert all(set(smaller) <= set(larger) for smaller, larger in zip(libraries, libraries[1:]))
    assert libraries[0] == shown


def test_a_folder_too_small_for_ten_shown_parts_is_refused():
    with pytest.raises(parts.SplitError, match="the dev half holds 5 of its 10 parts"):
        library_size.libraries({f"part-{k}": None for k in range(10)})


def test_the_summary_counts_lone_and_cluttered_scenes_apart():
    data = {"kinds": ["single", "single", "clutter"],
            "rows": [{"models": 10, "found": [1, 0, 3], "counted": [1, 1, 4], "false": [0, 1, 1],
                      "ms": [100.0, 300.0, 200.0]}]}
    (row,) = library_size_report.summary(data)
    assert row["lone"] == (1, 2) and row["multi"] == (3, 4)
    assert row["false_per_scene"] == pytest.approx(2 / 3)
    assert row["median_ms"] == 200.0
    assert "| 10 | 1/2 = 0.50 | 3/4 = 0.75 | 0.67 | 200 | 200 |" in library_size_report.table(data)


def test_the_report_names_lone_scenes_as_the_results_file_does():
    from psorr.synthetic.mesh_scenes import SceneKind

    assert library_size_report.SINGLE == str(SceneKind.SINGLE)


def test_false_detections_are_counted_per_model_and_library():
    data = {"rows": [{"models": 10, "false_models": [["knob"], []]},
                     {"models": 39, "false_models": [["knob", "idler"], ["idler"]]}]}
    table = library_size_report.false_table(data)
    assert table.splitlines()[0] == "| model | 10 models | 39 models |"
    assert table.splitlines()[2:] == ["| idler | 0 | 2 |", "| knob | 1 | 1 |"]


def test_a_run_of_lone_scenes_only_reports_no_clutter_recall_rather_than_failing():
    data = {"kinds": ["single"], "rows": [{"models": 10, "found": [1], "counted": [1], "false": [0], "ms": [90.0]}]}
    assert "| 10 | 1/1 = 1.00 | 0/0 = nan |" in library_size_report.table(data)
