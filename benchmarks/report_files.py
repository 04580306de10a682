"""Writing a benchmark's results: its table printed, and written as NAME.md and NAME.json."""

from __future__ import annotations

import json
from pathlib import Path


def write_report(out: Path, name: str, lines: list[str], record: dict) -> str:
    """Print ``lines`` and write them to ``out``/NAME.md, and ``record`` to ``out``/NAME.json; returns the text."""
    text = "\n".join(lines)
    print(text)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}.md").write_text(text + "\n")
    (out / f"{name}.json").write_text(json.dumps(record, indent=1) + "\n")
    return text
