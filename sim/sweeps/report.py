"""A finished sweep at a glance: a table of grasp and place success for each value of each swept variable,
and a picture of grasp success against each."""

from __future__ import annotations

from pathlib import Path

GROUP_COLUMNS = {"tasks": "task", "seeds": "seed", "poses": "poses", "camera_height": "camera_height",
                 "resolution": "resolution", "occluder": "occluder", "noise": "noise", "method": "method"}


def summary_rows(episodes, swept: tuple[str, ...]) -> list[dict]:
    """Per swept variable (seeds left out) and value: episodes, picks, and grasp and place success over picks.
    With nothing swept, one row for the whole sweep. ``episodes`` is a pyarrow Table of episode rows."""
    rows = episodes.to_pylist()
    keys = [GROUP_COLUMNS[k] for k in swept if k != "seeds"] or [None]
    out = []
    for key in keys:
        values = sorted({r[key] for r in rows}, key=str) if key else ["all"]
        for value in values:
            group = [r for r in rows if key is None or r[key] == value]
            picks = sum(r["picks"] for r in group)
            out.append({"variable": key or "sweep", "value": value, "episodes": len(group), "picks": picks,
                        "grasp": sum(r["grasped"] for r in group) / picks if picks else 0.0,
                        "place": sum(r["placed"] for r in group) / picks if picks else 0.0})
    return out


def summary_table(rows: list[dict]) -> str:
    lines = [f"{'variable':<14} {'value':<22} {'episodes':>8} {'picks':>6} {'grasp':>6} {'place':>6}"]
    lines += [f"{r['variable']:<14} {str(r['value']):<22} {r['episodes']:>8} {r['picks']:>6} {r['grasp']:>6.0%} "
              f"{r['place']:>6.0%}" for r in rows]
    return "\n".join(lines)


def save_plot(rows: list[dict], path: Path) -> Path:
    """Grasp success against each swept variable, a panel each."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    variables = list(dict.fromkeys(r["variable"] for r in rows))
    fig, axes = plt.subplots(1, len(variables), figsize=(4 * len(variables), 3.2), squeeze=False)
    for ax, variable in zip(axes[0], variables):
        group = [r for r in rows if r["variable"] == variable]
        ax.bar([str(r["value"]) for r in group], [100 * r["grasp"] for r in group], color="#4c72b0")
        ax.set_ylim(0, 100)
        ax.set_ylabel("grasp success (%)")
        ax.set_xlabel(variable)
        for k, r in enumerate(group):
            ax.text(k, 100 * r["grasp"] + 2, f"{r['picks']} picks", ha="center", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
