"""What every benchmark table shares: the results files, a markdown table, a success fraction."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results"


class TableError(Exception):
    """A placeholder names no table, or its results file is missing or malformed."""


def load(name: str) -> dict:
    path = RESULTS / f"{name}.json"
    if not path.exists():
        raise TableError(f"{path.relative_to(ROOT)} is missing: run `python benchmarks/{name}.py` (or `make bench`)")
    return json.loads(path.read_text())


def benchmark_module(name: str):
    """benchmarks/<name>.py loaded as a module: a benchmark's own report code, so the site prints what it does."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def table(header: list[str], rows: list[list], align: str = "") -> str:
    """A markdown table; ``align`` gives one character per column, 'r' for right-aligned numbers."""
    align = align or "l" * len(header)
    rule = ["---:" if a == "r" else "---" for a in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(rule) + " |"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def frac(k: int, n: int) -> str:
    return f"{k}/{n} = {k / n:.2f}" if n else "-"


def met(flag: bool) -> str:
    return "**met**" if flag else "**missed**"
