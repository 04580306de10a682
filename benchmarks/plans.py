"""Process plans: how often each shipped plan reaches its goal, with recognised poses and the person about.

Runs every plan in ``tasks/plans/`` (the printed-parts plan only when ``../shared/cad`` is there) for
``--seeds`` seeded runs on one core (``--plans NAME ...``: only those, the others' rows kept from the last
run), and writes ``benchmarks/results/plans.json`` and ``plans.md``: per
plan, the goals reached, the actions that failed, the replans, the wall time a run, and how many parts
the goal does not name were moved (a wrong-colour twin picked, a neighbour pushed). Targets: each goal
reached in at least 9 of 10 runs; the wrong-colour twin never picked.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import numpy as np
from tqdm import tqdm

from sim.errors import TaskFileError
from sim.plans import load_plan, run_plan

ROOT = Path(__file__).resolve().parents[1]

RESULTS = ROOT / "benchmarks" / "results"


def _run(plan, seeds: int) -> dict:
    reached, replans, walls, failed, moved = 0, 0, [], {}, 0
    for seed in tqdm(range(seeds), desc=plan.path.stem, file=sys.stderr):
        result = run_plan(plan, np.random.default_rng([seed, 0]), poses="recognized", occluder=True)
        reached += result.goal_reached
        replans += result.replans
        walls.append(result.wall_s)
        for a in result.actions:
            if a.outcome not in ("grasped", "placed"):
                failed[a.outcome] = failed.get(a.outcome, 0) + 1
        moved += len(result.others_moved)
    return {"plan": plan.path.stem, "runs": seeds, "goal_reached": reached, "replans": replans,
            "failed_actions": failed, "others_moved": moved, "wall_s_median": float(np.median(walls))}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--plans", nargs="+", metavar="NAME", help="run only these plans (file stems)")
    args = parser.parse_args(argv)
    rows, start = [], time.perf_counter()
    kept = {}
    if args.plans and (RESULTS / "plans.json").is_file():
        kept = {r["plan"]: r for r in json.loads((RESULTS / "plans.json").read_text())["rows"]}
    for path in sorted((ROOT / "tasks" / "plans").glob("*.yaml")):
        if args.plans and path.stem not in args.plans:
            if path.stem in kept:
                rows.append(kept[path.stem])
            continue
        try:
            plan = load_plan(path)
        except TaskFileError as exc:
            print(f"skipped {path.name}: {exc}", file=sys.stderr)
            continue
        rows.append(_run(plan, args.seeds))
    lines = [f"{args.seeds} seeded runs of each shipped plan, recognised poses, the person about, 1 core "
             f"({time.perf_counter() - start:.0f} s in all)", "",
             "| plan | goal reached | replans | failed actions | parts not in the goal moved | wall s a run (median) |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        failed = ", ".join(f"{k}: {v}" for k, v in r["failed_actions"].items()) or "none"
        lines.append(f"| {r['plan']} | {r['goal_reached']}/{r['runs']} | {r['replans']} | {failed} | "
                     f"{r['others_moved']} | {r['wall_s_median']:.1f} |")
    met = all(r["goal_reached"] >= 0.9 * r["runs"] for r in rows)
    lines += ["", f"Target: each goal reached in at least 9 of 10 runs: {'met' if met else 'MISSED'}"]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "plans.json").write_text(json.dumps({"seeds": args.seeds, "rows": rows}, indent=1) + "\n")
    (RESULTS / "plans.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
