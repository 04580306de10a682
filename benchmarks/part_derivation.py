"""What a new part costs the cell: collision hulls (CoACD) and grasps (synthesised, tried in MuJoCo) from its
mesh alone, on one core, from an empty cache; and the same call again, read from the cache.

The parts are a task's mesh parts (default ``tasks/printed_parts.yaml``, which needs ``../shared/cad``) and
any more meshes given with ``--mesh`` (millimetres). Each is derived with ``sim.parts.derive.derive_part``
into a fresh cache folder, so nothing of an earlier run is reused. Writes
``benchmarks/results/part_derivation.json`` and ``.md``: per part, the seconds of the hulls, of the grasps
and in all, the milliseconds of the cached call, the hulls and the grasps kept. Target (issue 33): grasp
synthesis and collision decomposition under 60 s per new part on one core, and nothing once cached.

    python benchmarks/part_derivation.py [--task tasks/printed_parts.yaml] [--mesh PATH.stl ...]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
TARGET_S = 60.0  # the most a new part's hulls and grasps may take


def _parts(task: Path, meshes: list[Path]) -> list:
    from sim.parts.source import MeshPart
    from sim.world.tasks import load_task

    parts = list(load_task(task).world.mesh_parts)
    return parts + [MeshPart(path.resolve(), "mm", path.stem) for path in meshes]


def _derived(part) -> dict:
    """Derive ``part`` into the current (empty) cache, then again from it; the row of the report."""
    from sim.parts.derive import cache_folder, derive_part

    start = time.perf_counter()
    cell_part = derive_part(part, progress=None)
    total = time.perf_counter() - start
    start = time.perf_counter()
    derive_part(part, progress=None)
    cached_ms = (time.perf_counter() - start) * 1e3
    collision = json.loads((cache_folder(part) / "collision" / "collision.json").read_text())
    return {"part": part.name, "hulls_s": collision["seconds"], "grasps_s": total - collision["seconds"],
            "total_s": total, "cached_ms": cached_ms, "hulls": len(cell_part.collision_files),
            "grasps": len(cell_part.grasps), "remeshed": collision.get("remeshed", False)}


def main(argv=None) -> int:
    from tqdm import tqdm

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", type=Path, default=ROOT / "tasks" / "printed_parts.yaml")
    parser.add_argument("--mesh", type=Path, nargs="*", default=[], help="more meshes, in millimetres")
    args = parser.parse_args(argv)
    parts = _parts(args.task, args.mesh)
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        os.environ["PSORR_CACHE"] = cache
        for part in tqdm(parts, desc="parts derived from an empty cache", file=sys.stderr):
            rows.append(_derived(part))
    data = {"target_s": TARGET_S, "rows": rows, "conditions": f"run {time.strftime('%Y-%m-%d')}, 1 core"}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "part_derivation.json").write_text(json.dumps(data, indent=1) + "\n")
    lines = [f"{len(rows)} parts, each from an empty cache, 1 core", "",
             "| part | hulls s | grasps s | in all s | cached ms | hulls | grasps |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['part']} | {r['hulls_s']:.1f} | {r['grasps_s']:.1f} | {r['total_s']:.1f} | {r['cached_ms']:.0f} | "
              f"{r['hulls']} | {r['grasps']} |" for r in rows]
    over = [r["part"] for r in rows if r["total_s"] >= TARGET_S]
    lines += ["", f"Target: under {TARGET_S:.0f} s a new part: "
              + ("met" if not over else f"MISSED by {', '.join(over)}")]
    (RESULTS / "part_derivation.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
