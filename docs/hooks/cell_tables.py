"""The robot cell's benchmark tables (grasp tolerance, episodes), each from its ``benchmarks/results/*.json``."""

from __future__ import annotations

from tables_common import frac, load, table

# ---- grasp tolerance (benchmarks/grasp_tolerance.py) -----------------------------------------------------------

SWEEP_UNITS = {"translation": "mm", "yaw": "deg", "tilt": "deg"}


def grasp_tolerance() -> str:
    data = load("grasp_tolerance")
    trials, rows = data["trials"], []
    for sweep, unit in SWEEP_UNITS.items():
        parts = {t["part"] for t in trials if t["sweep"] == sweep}
        for level in data["grid"][sweep]:
            at = [t for t in trials if t["level"] == level and t["part"] in parts
                  and (t["sweep"] == sweep or (level == 0 and t["sweep"] == "zero"))]
            side = {s: [t for t in at if t.get("vs_closing") == s] for s in ("along", "across")}
            split = [frac(sum(t["placed"] for t in side[s]), len(side[s])) if side[s] else "-" for s in side]
            rows.append([sweep, f"{level} {unit}", len(at), frac(sum(t["grasped"] for t in at), len(at)),
                         frac(sum(t["placed"] for t in at), len(at)), *split])
    return table(["sweep", "error", "picks", "grasped", "placed", "placed, error along closing",
                  "placed, across closing"], rows, "lrrrrrr")


# ---- episodes (benchmarks/episodes.py) -------------------------------------------------------------------------

def episodes(stem: str = "episodes") -> str:
    rows = []
    for r in load(stem)["rows"]:
        error = "0" if r["mode"] == "oracle" else \
            f"{r['pose_error_mm_median']:.1f} mm, {r['rot_error_deg_median']:.1f} deg"
        rows.append([r["mode"], r["episodes"], r["picks"], f"{r['grasp_success_rate']:.0%}",
                     f"{r['place_success_rate']:.0%}", error,
                     f"{r['wall_s_per_episode']:.1f} / {r['wall_s_median']:.1f} / {r['wall_s_max']:.1f}",
                     f"{r['looks_per_episode']:.1f}", r["occupied_looks"], r["protective_stops"],
                     f"{r['min_human_clearance_mm']:.0f} mm"])
    return table(["poses", "episodes", "picks", "grasped", "placed", "pose error (median)",
                  "wall s per episode (mean / median / max)", "looks per episode", "waits for the person",
                  "protective stops", "closest the arm came to the person"], rows, "lrrrrrrrrrr")


def episodes_per_part(stem: str = "episodes") -> str:
    per_part = load(stem)["per_part"]
    parts = sorted({p for counts in per_part.values() for p in counts})
    rows = []
    for part in parts:
        row = [part]
        for mode in per_part:
            picks, grasped, placed = per_part[mode][part]
            row += [f"{grasped}/{picks}", f"{placed}/{picks}"]
        rows.append(row)
    header = ["part"] + [f"{mode} {what}" for mode in per_part for what in ("grasped", "placed")]
    return table(header, rows, "l" + "r" * (len(header) - 1))


def episodes_in_hand() -> str:
    looks = [p for p in load("episodes")["picks"].get("recognized", []) if p.get("in_hand")]
    rows = [[p["episode"], p["part"], f"{p['in_hand']['yaw_deg']:.0f}", p["in_hand"]["telling_pixels"],
             f"{p['in_hand']['score']:.2f}", "settled" if p["in_hand"]["settled"] else "undecided (estimate kept)",
             "yes" if p["in_hand"]["chosen"] else "no", "yes" if p["placed"] else "no"] for p in looks]
    return table(["episode", "part", "wrist yaw deg", "telling pixels", "score", "look", "held the other way round",
                  "placed"], rows, "rlrrrlll")


def episodes_failures(stem: str) -> str:
    """Per mode, the failed picks by reason (benchmarks/episode_failures.py)."""
    failures = load(stem)["failures"]
    reasons = list(next(iter(failures.values())))
    rows = [[mode, sum(counts.values()), *(counts[r] for r in reasons)] for mode, counts in failures.items()]
    return table(["poses", "failed picks", *reasons], rows, "l" + "r" * (len(reasons) + 1))


def task_tables(task: str) -> dict:
    """The placeholders of one task's episode tables: ``episodes-<task>``, ``-per-part`` and ``-failures``."""
    stem, name = f"episodes_{task}", f"episodes-{task.replace('_', '-')}"
    return {name: lambda: episodes(stem), f"{name}-per-part": lambda: episodes_per_part(stem),
            f"{name}-failures": lambda: episodes_failures(stem)}


def plans() -> str:
    """benchmarks/plans.py: how often each shipped process plan reaches its goal."""
    data = load("plans")
    rows = [[f"`{r['plan']}`", f"{r['goal_reached']}/{r['runs']}", r["replans"],
             ", ".join(f"{k}: {v}" for k, v in r["failed_actions"].items()) or "none", r["others_moved"],
             f"{r['wall_s_median']:.1f}"] for r in data["rows"]]
    return table(["plan", "goal reached", "replans", "failed actions", "parts not in the goal moved",
                  "wall s a run (median)"], rows, "lrrlrr")


def sweep_throughput() -> str:
    """benchmarks/sweep_throughput.py: one local worker against two."""
    data = load("sweep_throughput")
    rows = [[r["workers"], f"{r['wall_s']:.0f}", f"{r['episodes_per_min']:.1f}", f"{r['episode_s']:.2f}"]
            for r in data["rows"]]
    return table(["workers", "wall s a run", "episodes a minute", "episode s (mean)"], rows, "rrrr") + (
        f"\n\n{data['episodes']} one-part episodes, {data['rounds']} runs of each in the order 1, 2, 2, 1 "
        f"workers; speed-up {data['speedup']:.3f}x (target at least 1.8x: "
        f"{'met' if data['speedup'] >= 1.8 else 'missed'}); two processes of a plain Python loop "
        f"{data['machine_speedup']:.2f}x one's speed on this machine in the same run")


def soak() -> str:
    """benchmarks/soak.py: crashes, lost episodes and each worker's memory over a long run."""
    data = load("soak")
    rows = [[k, len(c), f"{c[0]:.0f}", f"{c[len(c) // 2]:.0f}", f"{c[-1]:.0f}"] for k, c in enumerate(data["rss_mb"])]
    out = table(["worker", "episodes", "MB after its first", "after half", "at the end"], rows, "rrrrr")
    failed = ", ".join(f"{k}: {v}" for k, v in data["failures"].items()) or "none"
    return out + (f"\n\n{data['episodes']} episodes on {data['workers']} workers in {data['wall_s'] / 60:.0f} min: "
                  f"{len(data['crashes'])} crashed, {data['lost']} lost, memory "
                  f"{'flat' if data['flat'] else 'growing'}; failed picks: {failed}.")


def part_derivation() -> str:
    """benchmarks/part_derivation.py: a new part's hulls and grasps from an empty cache, and the cached call."""
    data = load("part_derivation")
    rows = [[r["part"], f"{r['hulls_s']:.1f}", f"{r['grasps_s']:.1f}", f"{r['total_s']:.1f}", f"{r['cached_ms']:.0f}",
             r["hulls"], r["grasps"]] for r in data["rows"]]
    over = [r["part"] for r in data["rows"] if r["total_s"] >= data["target_s"]]
    verdict = "met" if not over else f"missed by {', '.join(over)}"
    return table(["part", "hulls s", "grasps s", "in all s", "cached ms", "hulls", "grasps"], rows, "lrrrrrr") + (
        f"\n\n{data['conditions']}; target under {data['target_s']:.0f} s a new part: {verdict}")
