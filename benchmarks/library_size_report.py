"""The library-size benchmark's summary, table and picture (benchmarks/library_size.py), apart from the script so
that the docs' hook renders the table without pinning mkdocs to one core."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np

SINGLE = "single"  # str(psorr.synthetic.mesh_scenes.SceneKind.SINGLE), as the results file holds it


def recall(found_counted: tuple[int, int]) -> float:
    """found / counted, NaN when the run counted none (a run of lone scenes only has no clutter)."""
    found, counted = found_counted
    return found / counted if counted else float("nan")


def summary(data: dict) -> list[dict]:
    """Per library: its size, lone and clutter-and-occluded (found, counted), false detections a scene, ms."""
    lone = np.array([k == SINGLE for k in data["kinds"]])
    out = []
    for row in data["rows"]:
        found, counted = np.array(row["found"]), np.array(row["counted"])
        out.append({"models": row["models"], "lone": (int(found[lone].sum()), int(counted[lone].sum())),
                    "multi": (int(found[~lone].sum()), int(counted[~lone].sum())),
                    "false_per_scene": sum(row["false"]) / len(row["false"]),
                    "median_ms": float(np.median(row["ms"])), "mean_ms": float(np.mean(row["ms"]))})
    return out


def table(data: dict) -> str:
    """The markdown table of :func:`summary` (the docs' hook renders this one)."""
    lines = ["| models in the library | lone | clutter and occluded (>= 30% seen) | false / scene | median ms "
             "| mean ms |", "|---:|---:|---:|---:|---:|---:|"]
    for s in summary(data):
        (lf, ln), (mf, mn) = s["lone"], s["multi"]
        lines.append(f"| {s['models']} | {lf}/{ln} = {recall(s['lone']):.2f} | {mf}/{mn} = {recall(s['multi']):.2f} | "
                     f"{s['false_per_scene']:.2f} | {s['median_ms']:.0f} | {s['mean_ms']:.0f} |")
    return "\n".join(lines)


def false_table(data: dict) -> str:
    """Per model, its false detections over all scenes with each library (the docs' hook renders this one)."""
    rows = data["rows"]
    counts = [Counter(model for scene in row["false_models"] for model in scene) for row in rows]
    models = sorted(set().union(*counts), key=lambda m: (-counts[-1][m], m))
    lines = ["| model | " + " | ".join(f"{row['models']} models" for row in rows) + " |",
             "|---|" + "---:|" * len(rows)]
    lines += [f"| {m} | " + " | ".join(str(c[m]) for c in counts) + " |" for m in models]
    return "\n".join(lines)


def plot(data: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = summary(data)
    models = [r["models"] for r in rows]
    fig, (shares, times) = plt.subplots(1, 2, figsize=(10, 3.8))
    shares.plot(models, [recall(r["lone"]) for r in rows], "o-", label="lone")
    shares.plot(models, [recall(r["multi"]) for r in rows], "s-", label="clutter and occluded")
    shares.plot(models, [r["false_per_scene"] for r in rows], "^--", label="false detections a scene")
    shares.set(xlabel="models in the library", ylim=(0, 1.05), title="the same scenes, larger libraries")
    shares.legend(loc="lower left")
    times.plot(models, [r["median_ms"] for r in rows], "o-", label="median")
    times.plot(models, [r["mean_ms"] for r in rows], "s-", label="mean")
    times.set(xlabel="models in the library", ylabel="ms a scene, one core", ylim=(0, None), title="time")
    times.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
