"""Sweep throughput: the same grid of short episodes on one local process and on two, on this machine.

Runs ``--episodes`` one-part episodes (``tasks/sweeps/one_part.yaml``, recognised poses, the person about)
through ``psorr-sim sweep``'s local pool of 1 and of 2 worker processes, each into a fresh folder, and writes
``benchmarks/results/sweep_throughput.json`` and ``.md``: episodes a minute and the speed-up. Target: 2
workers give at least 1.8x one's throughput on 2 cores. Each worker runs its numerical libraries on one
thread and pays its own start (imports, the models read from the cache), as in a user's sweep.

The runs go 1, 2, 2, 1 workers (``--rounds`` 2) and each arm's walls are summed, so that the machine's
speed drifting over the minutes of a run weighs on both arms alike. Beside the sweep, the same order of runs
of a plain Python loop, alone and two at once, gives what this machine's two cores allow any two processes.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
TARGET = 1.8
SPIN = "x = 0\nfor i in range(20_000_000):\n    x += i * i\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--episodes", type=int, default=12)
    parser.add_argument("--rounds", type=int, default=2, help="rounds of 1, 2, 2, 1 workers count as 2")
    args = parser.parse_args(argv)
    order = [1, 2, 2, 1] * (args.rounds // 2) + [1, 2] * (args.rounds % 2)
    rows = sweep_rows(args.episodes, order)
    machine = spin_speedup(order)
    speedup = rows[1]["episodes_per_min"] / rows[0]["episodes_per_min"]
    lines = [f"{args.episodes} one-part episodes (recognised poses, the person about), local pool, "
             f"{args.rounds} runs of each", "",
             "| workers | wall s a run | episodes a minute | episode s (mean) |", "|---:|---:|---:|---:|"]
    lines += [f"| {r['workers']} | {r['wall_s']:.0f} | {r['episodes_per_min']:.1f} | {r['episode_s']:.2f} |"
              for r in rows]
    lines += ["", f"Two processes of a plain Python loop on this machine: {machine:.2f}x one's speed",
              f"Speed-up on 2 cores: {speedup:.3f}x; target at least {TARGET}x: "
              f"{'met' if speedup >= TARGET else 'MISSED'}"]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "sweep_throughput.json").write_text(json.dumps(
        {"episodes": args.episodes, "rounds": args.rounds, "rows": rows, "speedup": speedup,
         "machine_speedup": machine}, indent=1) + "\n")
    (RESULTS / "sweep_throughput.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


def sweep_rows(episodes: int, order: list[int]) -> list[dict]:
    """For 1 and 2 workers: the mean wall of a run over ``order``'s runs, throughput, and an episode's mean
    wall as the episode measured it."""
    import pyarrow.parquet as pq

    from sim.sweeps import EpisodeSpec, run_local

    task = str(ROOT / "tasks" / "sweeps" / "one_part.yaml")
    specs = [EpisodeSpec(task, seed, "recognized", None, "640x480", True) for seed in range(episodes)]
    run_local(specs[:1], Path(tempfile.mkdtemp()), workers=1)  # the models and grasps into the cache first
    walls: dict[int, list[float]] = {1: [], 2: []}
    episode_s: dict[int, list[float]] = {1: [], 2: []}
    for workers in order:
        out = Path(tempfile.mkdtemp())
        start = time.perf_counter()
        run_local(specs, out, workers=workers, pool=True)
        walls[workers].append(time.perf_counter() - start)
        episode_s[workers] += [pq.read_table(p).column("wall_s")[0].as_py()
                               for p in (out / "rows").glob("*.episode.parquet")]
        print(f"{workers} worker(s): {walls[workers][-1]:.0f} s", file=sys.stderr, flush=True)
    return [{"workers": w, "wall_s": sum(walls[w]) / len(walls[w]),
             "episodes_per_min": 60 * episodes * len(walls[w]) / sum(walls[w]),
             "episode_s": sum(episode_s[w]) / len(episode_s[w])} for w in (1, 2)]


def spin_speedup(order: list[int]) -> float:
    """Two processes' throughput of a plain Python loop over one's, run in ``order``."""
    walls: dict[int, float] = {1: 0.0, 2: 0.0}
    for copies in order:
        start = time.perf_counter()
        procs = [subprocess.Popen([sys.executable, "-c", SPIN]) for _ in range(copies)]
        for proc in procs:
            proc.wait()
        walls[copies] += time.perf_counter() - start
    return 2 * walls[1] / walls[2]


if __name__ == "__main__":
    sys.exit(main())
