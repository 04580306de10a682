"""Soak: many short episodes through the sweep's local pool, watching for crashes, lost episodes and memory
that grows.

Runs ``--episodes`` one-part episodes (``tasks/sweeps/one_part.yaml``: recognition on, the person about) on
``--workers`` processes, each worker reporting its resident memory after every episode. Writes
``benchmarks/results/soak.json``, ``soak.md`` (the failure table and each worker's memory at the start,
middle and end) and ``soak.png`` (the memory curve). Target: no crash, no episode lost, and each worker's
memory flat: its last tenth of episodes within 10% of its second tenth (the first tenth warms caches up).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
from tqdm import tqdm

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
TASK = ROOT / "tasks" / "sweeps" / "one_part.yaml"
FLAT = 0.10  # a worker's memory is flat when its last tenth of episodes is within this of its second tenth


def _rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def soak_episode(seed: int) -> dict:
    from sim.sweeps import EpisodeSpec, run_episode_rows

    spec = EpisodeSpec(str(TASK), seed, "recognized", None, "640x480", True)
    try:
        episode, picks = run_episode_rows(spec)
        failures = [p["note"].split(":")[0] for p in picks if not p["placed"]]
        error = ""
    except Exception as exc:  # a crash is what the soak looks for: report it, do not lose the episode
        failures, error = [], f"{exc.__class__.__name__}: {exc}"
    return {"seed": seed, "pid": os.getpid(), "rss_mb": _rss_mb(), "failures": failures, "error": error}


def _flat(curve: list[float]) -> bool:
    tenth = max(1, len(curve) // 10)
    early, late = np.median(curve[tenth:2 * tenth] or curve[:tenth]), np.median(curve[-tenth:])
    return bool(late <= early * (1 + FLAT))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    start, rows = time.perf_counter(), []
    with ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(soak_episode, seed) for seed in range(args.episodes)]
        for future in tqdm(as_completed(futures), total=len(futures), desc="soak", file=sys.stderr):
            rows.append(future.result())
    wall = time.perf_counter() - start
    rows.sort(key=lambda r: r["seed"])
    curves = {pid: [r["rss_mb"] for r in rows if r["pid"] == pid] for pid in sorted({r["pid"] for r in rows})}
    crashes = [r for r in rows if r["error"]]
    failures = Counter(f for r in rows for f in r["failures"])
    lost = args.episodes - len(rows)
    flat = all(_flat(c) for c in curves.values())
    _picture(curves)
    lines = [f"{args.episodes} one-part episodes (recognition on, the person about) on {args.workers} processes, "
             f"{wall:.0f} s in all", "", "| worker | episodes | MB after its first | after half | at the end | flat |",
             "|---|---:|---:|---:|---:|---|"]
    for k, curve in enumerate(curves.values()):
        lines.append(f"| {k} | {len(curve)} | {curve[0]:.0f} | {curve[len(curve) // 2]:.0f} | {curve[-1]:.0f} | "
                     f"{'yes' if _flat(curve) else 'NO'} |")
    lines += ["", "| outcome | episodes or picks |", "|---|---:|", f"| crashed episodes | {len(crashes)} |",
              f"| lost episodes | {lost} |"] + [f"| pick failed: {k} | {v} |" for k, v in failures.most_common()]
    met = not crashes and not lost and flat
    lines += ["", f"Target: no crash, no episode lost, memory flat in every worker: {'met' if met else 'MISSED'}"]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "soak.json").write_text(json.dumps({"episodes": args.episodes, "workers": args.workers, "wall_s": wall,
                                                   "rss_mb": list(curves.values()), "crashes": crashes,
                                                   "lost": lost, "failures": dict(failures), "flat": flat}) + "\n")
    (RESULTS / "soak.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


def _picture(curves: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.2))
    for k, curve in enumerate(curves.values()):
        ax.plot(curve, label=f"worker {k}")
    ax.set_xlabel("episodes the worker has run")
    ax.set_ylabel("resident memory (MB)")
    ax.set_ylim(bottom=0)
    ax.legend()
    fig.tight_layout()
    fig.savefig(RESULTS / "soak.png", dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
