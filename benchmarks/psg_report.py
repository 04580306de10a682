"""The PSG benchmark's report (benchmarks/psg.py): recall and time of PSORR, PSG and AUTO per model, the
crossover (the fewest primitives from which PSG is the faster method), and whether AUTO, which picks by the
model's primitive count, finds as much as the better of the two.

Time is compared only where a method's own search ran: a lone part that the resting-pose trial settles
(docs/decisions/0066-resting-poses-first.md) runs the same code in both methods, and which of the two then
comes out faster is the machine's noise.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from report_files import write_report

METHODS = ("psorr", "psg", "auto", "cliques")
TIMED = ("psorr", "psg", "auto")
HEADER = ["model", "planes", "cylinders", "PSORR found", "PSG found", "PSG false", "auto found", "auto matches",
          "searched", "PSORR / PSG / auto mean ms, searched", "PSORR / PSG / auto median ms", "cliques alone found"]


def _table_row(r: dict) -> list[str]:
    """One model's row of the table (``report`` has set its searched scenes and their mean times)."""
    own, n = r["searched_mean_ms"], r["seeds"]
    return [r["model"], str(r["planes"]), str(r["cylinders"]), f"{r['psorr']['found']}/{n}",
            f"{r['psg']['found']}/{n}", str(r["psg"]["false"]), f"{r['auto']['found']}/{n}",
            "cliques, then pairs" if r["auto_cliques"] else "pairs",
            f"{len(r['searched_scenes'])}/{n}",
            " / ".join(f"{own[m]:.0f}" for m in TIMED) if own else "the same code",
            " / ".join(f"{np.median(r[m]['ms']):.0f}" for m in TIMED), f"{r['cliques']['found']}/{n}"]


def report(rows: list[dict], out: Path, auto_primitives: int) -> None:
    """Write psg.md, psg.json and psg.png from ``rows`` (one per model; ``auto_cliques``: whether AUTO matched
    its cliques); ``auto_primitives``: the fewest primitives whose models AUTO matches by their cliques."""
    rows = sorted(rows, key=lambda r: (_primitives(r), r["model"]))
    for r in rows:  # once per row, for the verdicts and the docs' table alike
        scenes = r["searched_scenes"] = _searched(r)
        r["searched_mean_ms"] = {m: _mean(r[m], scenes) for m in TIMED} if scenes else None
    lines = ["PSG matching against PSORR, and AUTO, each model alone, a library of 10 models, 1 core", "",
             "| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
    cells = [_table_row(r) for r in rows]
    lines += ["| " + " | ".join(c) + " |" for c in cells]
    verdicts = [_recall(rows), *_speed(rows), _auto(rows, auto_primitives)]
    lines += ["", *[f"- {v}" for v in verdicts]]
    write_report(out, "psg", lines, {"rows": rows, "verdicts": verdicts, "auto_primitives": auto_primitives,
                                     "table": {"header": HEADER, "cells": cells}})
    _plot(rows, auto_primitives, out / "psg.png")


def _plot(rows: list[dict], auto_primitives: int, path: Path) -> None:
    """Each method's mean time over a model's searched scenes against the model's primitive count, with AUTO's
    bar; models whose every scene the resting-pose trial settled have no point."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    searched = [r for r in rows if r["searched_scenes"]]
    # Models of one primitive count side by side, and each model's three methods joined by a line.
    x = {}
    for r in searched:
        same = [q["model"] for q in searched if _primitives(q) == _primitives(r)]
        x[r["model"]] = _primitives(r) + 0.8 * (same.index(r["model"]) - (len(same) - 1) / 2)
    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    for r in searched:
        ms = [r["searched_mean_ms"][m] for m in TIMED]
        ax.plot([x[r["model"]]] * 2, [min(ms), max(ms)], color="lightgray", lw=1, zorder=0)
        ax.annotate(r["model"], (x[r["model"]], min(ms)), textcoords="offset points", xytext=(0, -12),
                    ha="center", fontsize=7)
    for method, marker in zip(TIMED, "osd"):
        ax.plot([x[r["model"]] for r in searched], [r["searched_mean_ms"][method] for r in searched], marker,
                label=method.upper(), ms=7, alpha=0.8)
    low = min(min(r["searched_mean_ms"].values()) for r in searched) if searched else 0.0
    ax.set_ylim(bottom=0.85 * low)  # room for the names under the points
    ax.axvline(auto_primitives - 0.75, color="gray", ls="--", lw=0.8)
    ax.text(auto_primitives - 0.6, ax.get_ylim()[1], "AUTO: cliques from here", va="top", fontsize=7, color="gray")
    ax.set_xlabel("model primitives (planes + cylinders)")
    ax.set_ylabel("mean ms over the searched scenes")
    ax.set_title("PSORR, PSG and AUTO on lone models (1 core)", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _recall(rows: list[dict]) -> str:
    total = {m: sum(r[m]["found"] for r in rows) for m in METHODS}
    n = sum(r["seeds"] for r in rows)
    return (f"recall: PSORR {total['psorr']}/{n}, PSG {total['psg']}/{n}, AUTO {total['auto']}/{n}, PSG's cliques "
            f"alone {total['cliques']}/{n} ({sum(r['cliques']['false'] for r in rows)} false)")


def _speed(rows: list[dict]) -> list[str]:
    # Time only counts where PSG finds the model as often as PSORR (finding nothing is quick), and where a
    # method's own search ran: a scene the shared resting-pose trial settles runs the same code in both.
    both = [r for r in rows if r["psg"]["found"] >= r["psorr"]["found"] and r["searched_scenes"]]
    # Faster by the mean over those scenes, what a run of many scenes pays: of a few scenes, medians fell within
    # a few milliseconds of each other on the largest models, and which was lower changed run to run.
    faster = [r["model"] for r in both if r["searched_mean_ms"]["psg"] < r["searched_mean_ms"]["psorr"]]
    size = {r["model"]: _primitives(r) for r in both}
    # The fewest primitives from which on PSG is faster on every such model.
    crossover = min((c for c in size.values() if all(m in faster for m in size if size[m] >= c)), default=None)
    settled = [r["model"] for r in rows if not r["searched_scenes"]]
    return [f"the resting-pose trial settled every scene of {', '.join(settled)}, for every method alike"
            if settled else "each model has a scene that a method searched on its own",
            f"PSG finds {len(both)} of the {len(rows) - len(settled)} others as often as PSORR "
            f"({', '.join(r['model'] for r in both) or 'none'}); of those it is faster (mean time over the "
            f"scenes searched) on {', '.join(faster) or 'none'}",
            "no crossover: PSG is not the faster method on the largest model it finds as often" if crossover is None
            else f"crossover: PSG is the faster from {crossover} primitives on, on the models it finds as often"]


def _auto(rows: list[dict], auto_primitives: int) -> str:
    large = [r["model"] for r in rows if r["auto_cliques"]]
    fewer = [r["model"] for r in rows if r["auto"]["found"] < max(r["psorr"]["found"], r["psg"]["found"])]
    searched = [r for r in rows if r["searched_scenes"]]
    mean = {m: np.mean([r["searched_mean_ms"][m] for r in searched]) if searched else float("nan") for m in TIMED}
    return (f"AUTO matches the cliques of the models of at least {auto_primitives} primitives "
            f"({', '.join(large) or 'none'}) and pairs every model's; it finds "
            + (f"fewer than PSORR or PSG on {', '.join(fewer)}" if fewer else "each model as often as the better "
               "of PSORR and PSG") + "; mean over the searched models' mean times: "
            + ", ".join(f"{m.upper()} {mean[m]:.0f} ms" for m in TIMED))


def _primitives(row: dict) -> int:
    """The model's primitive count: its planes and cylinders."""
    return row["planes"] + row["cylinders"]


def _searched(row: dict) -> list[int]:
    """The scenes of ``row`` that PSORR, PSG or AUTO searched on its own (decomposed), by index."""
    return [k for k, flags in enumerate(zip(*(row[m]["searched"] for m in TIMED))) if any(flags)]


def _mean(method: dict, scenes: list[int]) -> float:
    return float(np.mean([method["ms"][k] for k in scenes]))
