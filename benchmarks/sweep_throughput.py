"""Sweep throughput: the same grid of short episodes on one local process and on two, on this machine.

Runs ``--episodes`` one-part episodes (``tasks/sweeps/one_part.yaml``, recognised poses, the person about)
through ``psorr-sim sweep``'s local pool of 1 and of 2 worker processes, each into a fresh folder, and writes
``benchmarks/results/sweep_throughput.json`` and ``.md``: episodes a minute and the speed-up. Target: 2
workers give at least 1.8x one's throughput on 2 cores. Each worker runs its numerical libraries on one
thread and pays its own start (imports, the models read from the cache), as in a user's sweep.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
TARGET = 1.8


def main(argv=None) -> int:
    from sim.sweeps import EpisodeSpec, run_local

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--episodes", type=int, default=12)
    args = parser.parse_args(argv)
    task = str(ROOT / "tasks" / "sweeps" / "one_part.yaml")
    specs = [EpisodeSpec(task, seed, "recognized", None, "640x480", True) for seed in range(args.episodes)]
    run_local(specs[:1], Path(tempfile.mkdtemp()), workers=1)  # the models and grasps into the cache first
    rows = []
    for workers in (1, 2):
        start = time.perf_counter()
        run_local(specs, Path(tempfile.mkdtemp()), workers=workers, pool=True)
        wall = time.perf_counter() - start
        rows.append({"workers": workers, "wall_s": wall, "episodes_per_min": 60 * args.episodes / wall})
        print(f"{workers} worker(s): {wall:.0f} s", file=sys.stderr, flush=True)
    speedup = rows[1]["episodes_per_min"] / rows[0]["episodes_per_min"]
    lines = [f"{args.episodes} one-part episodes (recognised poses, the person about), local pool", "",
             "| workers | wall s | episodes a minute |", "|---:|---:|---:|"]
    lines += [f"| {r['workers']} | {r['wall_s']:.0f} | {r['episodes_per_min']:.1f} |" for r in rows]
    lines += ["", f"Speed-up on 2 cores: {speedup:.2f}x; target at least {TARGET}x: "
              f"{'met' if speedup >= TARGET else 'MISSED'}"]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "sweep_throughput.json").write_text(json.dumps({"episodes": args.episodes, "rows": rows,
                                                               "speedup": speedup}, indent=1) + "\n")
    (RESULTS / "sweep_throughput.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
