"""Build the workpieces' collision geometry: a CoACD convex decomposition of every catalog mesh.

Run once from the repository root (a few minutes; CoACD is one of psorr's dependencies):

    .venv/bin/python assets/workpieces/build_collision.py [--only NAME ...] [--out DIR]

Writes assets/workpieces/collision/<name>_<k>.stl (binary STL, metres, the part's model frame)
and collision/index.json: per part its files, the SHA-256 of the source mesh (sim/world/assembly.py
refuses stale parts) and the settings used. MuJoCo takes each file's convex hull as one collision
geom, so a part keeps its cavities: the script fails if a point that must stay free (the middle
of the U-channel, the chassis tray, the bores) ends up inside a hull.

The decomposition is sim.parts.coacd_worker.decompose, the one users' parts get too (through
sim.parts.collision, with settings that scale with the part). CoACD's seed is fixed, so a rebuild gives
the same decomposition. The script reads the catalog JSON itself rather than importing psorr: coacd and
open3d in one process crash (std::bad_cast); sim.parts.coacd_worker imports neither psorr nor open3d.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from importlib import metadata
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import ConvexHull

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent))  # the checkout's sim, installed or not

from sim.parts.coacd_worker import decompose  # noqa: E402 - after the path it is found on

CATALOG = HERE / "catalog.json"
OUT_DIR = HERE / "collision"
SETTINGS = {"threshold": 0.05, "max_convex_hull": 16, "max_ch_vertex": 64, "decimate": True, "seed": 0}
"""CoACD arguments for every part: concavity 5% of the part's size, at most 16 hulls of 64 vertices."""
PREPROCESS = {"transformer": 40}
"""Parts remeshed first (CoACD's voxel preprocess at this resolution, about 1.75 mm voxels): the
1 mm gaps between the transformer's coils and its core stall CoACD's search for minutes."""
FREE_POINTS = {
    "u_channel": [(0.0, 0.0, 0.017), (0.05, 0.0, 0.01), (-0.05, 0.0, 0.025)],
    "chassis": [(0.0, 0.0, 0.02), (0.05, 0.02, 0.01)],
    "flanged_hub": [(0.0, 0.0, 0.025)],
    "bushing": [(0.0, 0.0, 0.018)],
    "pipe_tee": [(-0.04, 0.0, 0.0209), (0.0, 0.04, 0.0209)],
}
"""Model-frame points (m) inside a part's cavities that no collision hull may contain."""


def inside_hull(vertices: np.ndarray, points: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """(N,) bool: which (N, 3) points lie inside the convex hull of (M, 3) vertices (metres)."""
    equations = ConvexHull(vertices).equations  # outward normals: n . x + d <= 0 inside
    return np.all(points @ equations[:, :3].T + equations[:, 3] <= tol, axis=1)


def settings_of(name: str) -> dict:
    """CoACD's keyword arguments for the part ``name``: SETTINGS, remeshed first if PREPROCESS names it."""
    if name in PREPROCESS:
        return {**SETTINGS, "preprocess_mode": "on", "preprocess_resolution": PREPROCESS[name]}
    return {**SETTINGS, "preprocess_mode": "off"}


def build(name: str, entry: dict, out_dir: Path) -> dict:
    """Decompose one part, check its free points, write its STL files; return its index entry."""
    source = (HERE / entry["mesh"]).resolve()
    mesh = trimesh.load(source, force="mesh")
    start = time.perf_counter()
    hulls = decompose(mesh, settings_of(name))
    seconds = time.perf_counter() - start
    free = np.array(FREE_POINTS.get(name, np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)
    for k, hull in enumerate(hulls):
        blocked = free[inside_hull(hull.vertices, free)]
        if len(blocked):
            raise SystemExit(f"{name}: hull {k} fills the cavity at {blocked.tolist()} m; lower the threshold")
    for old in out_dir.glob(f"{name}_*.stl"):
        old.unlink()
    files = []
    for k, hull in enumerate(hulls):
        path = out_dir / f"{name}_{k}.stl"
        path.write_bytes(hull.export(file_type="stl"))
        files.append(path.name)
    volume = float(sum(h.volume for h in hulls))
    print(f"{name}: {len(hulls)} hulls, {sum(len(h.vertices) for h in hulls)} vertices, "
          f"hull volume {volume / mesh.volume:.2f} x the mesh's, {seconds:.0f} s", file=sys.stderr)
    return {
        "files": files,
        "source_mesh": entry["mesh"],
        "source_sha256": hashlib.sha256(source.read_bytes()).hexdigest(),
        "hull_volume_ratio": round(volume / mesh.volume, 4),
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", metavar="NAME", help="rebuild only these parts (others are kept)")
    parser.add_argument("--out", type=Path, default=OUT_DIR, metavar="DIR",
                        help="write the STL files and index.json here (default: assets/workpieces/collision)")
    args = parser.parse_args(argv)
    catalog = json.loads(CATALOG.read_text())["parts"]
    names = args.only or sorted(catalog)
    unknown = sorted(set(names) - set(catalog))
    if unknown:
        raise SystemExit(f"unknown parts {unknown}; choose from {sorted(catalog)}")
    args.out.mkdir(exist_ok=True)
    index_path = args.out / "index.json"
    parts = json.loads(index_path.read_text())["parts"] if index_path.is_file() else {}
    index = {"generator": f"assets/workpieces/build_collision.py with coacd {metadata.version('coacd')}",
             "settings": SETTINGS, "preprocess_resolution": PREPROCESS, "parts": parts}
    for name in names:
        index["parts"][name] = build(name, catalog[name], args.out)
    index["parts"] = dict(sorted(index["parts"].items()))
    index_path.write_text(json.dumps(index, indent=1) + "\n")
    total = sum(p.stat().st_size for p in args.out.glob("*.stl"))
    print(f"wrote {index_path} and {total / 1e6:.2f} MB of STL", file=sys.stderr)


if __name__ == "__main__":
    main()
