"""What recording for Rerun costs: ``psorr recognize`` on the peers benchmark's scenes, with and without a
:class:`psorr.viz.RerunLogger` writing an ``.rrd``, on one core.

Each scene is recognised both ways, in turns that alternate which goes first, so a slow spell of the machine
falls on both. Writes ``benchmarks/results/rerun_overhead.json`` and ``.md``: the median time a scene each
way, the added share (total recorded time over total plain time, less 1), and the recordings' sizes; and
the size of one demo episode's recording (``psorr-sim run tasks/demo.yaml --rerun``, recognised poses, the
person about). Targets: recording adds at most 15%; an episode's recording of the demo task is under 50 MB.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import numpy as np
from peer_common import catalog_library, clutter_scene
from tqdm import tqdm

from psorr.recognize import Recognizer
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.viz import RerunLogger

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
TARGET = 0.15  # the most recording may add to a recognition's time
EPISODE_TARGET_MB = 50.0  # the most a demo episode's recording may take


def _episode_mb(folder: Path, seed: int = 0) -> float:
    """The size (MB) of one demo episode's recording, as ``psorr-sim run --rerun`` writes it."""
    path = folder / "episode.rrd"
    subprocess.run([sys.executable, "-m", "sim.cli", "run", str(ROOT / "tasks" / "demo.yaml"), "--episodes", "1",
                    "--seed", str(seed), "--occluder", "on", "--rerun", str(path)], check=True, cwd=ROOT,
                   stdout=subprocess.DEVNULL)
    return path.stat().st_size / 2**20


def _timed(recognizer, cloud, path: Path | None) -> tuple[float, list]:
    start = time.perf_counter()
    if path is None:
        found = recognizer.recognize(cloud, np.random.default_rng(0)).detections
    else:
        with RerunLogger(path) as logger:
            found = recognizer.recognize(cloud, np.random.default_rng(0), observer=logger).detections
    return (time.perf_counter() - start) * 1e3, [d.model for d in found]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--singles-seeds", type=int, default=2, help="seeded scenes per part, as the peers'")
    parser.add_argument("--clutter", type=int, default=6, help="4-part occluded clutter scenes, as the peers'")
    args = parser.parse_args(argv)
    catalog, meshes, library, _, _ = catalog_library()
    recognizer = Recognizer(library)
    scenes = [workpiece_scene(np.random.default_rng(2000 + 10 * k + s), meshes, [name])
              for k, name in enumerate(sorted(catalog)) for s in range(args.singles_seeds)]
    scenes += [clutter_scene(seed, catalog, meshes) for seed in range(args.clutter)]
    plain, recorded, sizes, same = [], [], [], 0
    with tempfile.TemporaryDirectory() as folder:
        # First-use costs paid before timing, both ways: importing rerun and starting its writer take about a
        # second once per process, which a sweep of scenes pays once, not per scene.
        _timed(recognizer, scenes[0].cloud, None)
        _timed(recognizer, scenes[0].cloud, Path(folder) / "warm.rrd")
        for k, scene in enumerate(tqdm(scenes, desc="scenes, plain and recorded", file=sys.stderr)):
            path = Path(folder) / f"scene_{k}.rrd"
            order = (None, path) if k % 2 == 0 else (path, None)
            runs = {str(p): _timed(recognizer, scene.cloud, p) for p in order}
            plain.append(runs["None"][0])
            recorded.append(runs[str(path)][0])
            same += runs["None"][1] == runs[str(path)][1]
            sizes.append(path.stat().st_size / 2**20)
        episode_mb = _episode_mb(Path(folder))
    added = sum(recorded) / sum(plain) - 1
    data = {"scenes": len(scenes), "plain_ms_median": float(np.median(plain)),
            "recorded_ms_median": float(np.median(recorded)), "added": added, "same_detections": same,
            "rrd_mb_median": float(np.median(sizes)), "rrd_mb_max": float(max(sizes)), "target": TARGET,
            "episode_rrd_mb": episode_mb, "episode_target_mb": EPISODE_TARGET_MB}
    lines = [f"{len(scenes)} scenes of the peers benchmark, 8-part library, 1 core", "",
             "| | median ms a scene |", "|---|---|",
             f"| plain | {data['plain_ms_median']:.0f} |", f"| recorded | {data['recorded_ms_median']:.0f} |", "",
             f"Recording adds {added:.1%} (target at most {TARGET:.0%}: {'met' if added <= TARGET else 'MISSED'}); "
             f"same detections in {same}/{len(scenes)} scenes; recordings {data['rrd_mb_median']:.1f} MB median, "
             f"{data['rrd_mb_max']:.1f} MB at most.", "",
             f"A demo episode's recording (seed 0, recognised poses, the person about): {episode_mb:.1f} MB (target "
             f"under {EPISODE_TARGET_MB:.0f} MB: {'met' if episode_mb < EPISODE_TARGET_MB else 'MISSED'})."]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "rerun_overhead.json").write_text(json.dumps(data, indent=1) + "\n")
    (RESULTS / "rerun_overhead.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
