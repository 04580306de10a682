"""The generalization benchmark's tables, from ``benchmarks/results/generalization.json`` by the benchmark's
own report code (benchmarks/generalization_report.py), so that the site and the script print the same."""

from __future__ import annotations

import importlib.util

from tables_common import ROOT, load


def _report():
    spec = importlib.util.spec_from_file_location("generalization_report",
                                                  ROOT / "benchmarks" / "generalization_report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _rendered(name: str):
    def render() -> str:
        return getattr(_report(), name)(load("generalization"))
    return render


TABLES = {"generalization-scenes": _rendered("scenes_lines"), "generalization": _rendered("methods_table"),
          "generalization-targets": _rendered("targets_table"), "generalization-sizes": _rendered("sizes_table"),
          "generalization-classes": _rendered("classes_table"), "generalization-parts": _rendered("parts_table"),
          "generalization-shapes": _rendered("shapes_table")}
