"""Point density: the same scene sampled at 0.3M, 1M, 3M and 10M points, on one core.

Three scenes, each at four densities:

- a lone 1 m table plane, tilted 20 degrees, 1 m away, with 2 mm Gaussian noise, sampled uniformly;
- the same plane with a 20 cm box on it (its top and two sides);
- seeded 4-part catalog clutter scenes with an arm across them (those of peers.py), rendered by a
  Kinect-v1-like sensor at 640x480, 1280x960, 2048x1536 and 3648x2736 pixels over the same field of view.

The table scenes are drawn with several noise seeds, since strips of a few voxels along a box's
edges come and go with the draw at any density. For each cloud it prints PSORR's primitive count
and decomposition time, the Open3D segment_plane loop's plane count and time (the decomposition
benchmark's peer), and, for the rendered scenes, PSORR's detections graded as in peers.py. The
targets: the same counts at 0.3M, 1M and 3M points, a 3M cloud decomposed in under 1 s, and the
same recall at every resolution.

    python benchmarks/density.py [--densities 0.3,1,3,10] [--draws 3] [--scenes 6] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import numpy as np
from decompose import open3d_plane_loop
from peer_common import catalog_library, clutter_scene, grade
from report_files import write_report
from tqdm import tqdm

from psorr.decomposition import DecomposeParams, decompose
from psorr.recognize import Recognizer
from psorr.sensing.camera import CameraIntrinsics
from psorr.types import PointCloud

ROOT = Path(__file__).resolve().parents[1]
KINECT_WIDTH, KINECT_FX = 640, 525.0
# Sensor sizes of about 0.3M, 1.2M, 3.1M and 10M pixels, all 4:3 like the Kinect's.
RESOLUTIONS = {0.3: (640, 480), 1: (1280, 960), 3: (2048, 1536), 10: (3648, 2736)}
TARGET_3M_MS = 1000.0


TILT = np.radians(20.0)
# Table frame to camera frame: the plane's normal turned to face the camera at the origin, which looks along +z,
# and tilted by TILT; the table's centre 1 m in front of the camera.
R_CAMERA_TABLE = np.array([[1, 0, 0], [0, np.cos(TILT), -np.sin(TILT)], [0, np.sin(TILT), np.cos(TILT)]]) @ np.diag(
    [1.0, -1.0, -1.0])
T_CAMERA_TABLE = np.array([0.0, 0.0, 1.0])
CAMERA_IN_TABLE = R_CAMERA_TABLE.T @ -T_CAMERA_TABLE  # (0, 0.34, 0.94): above the table, towards +y
BOX_SIDE = 0.2
# Off the camera's axis along +x, so that besides its top the box shows the camera its -x side and its +y side.
BOX_LOW = np.array([0.1, -0.1, 0.0])
BOX_HIGH = BOX_LOW + BOX_SIDE


def _hidden_by_box(points: np.ndarray) -> np.ndarray:
    """(N,) bool: table-frame points whose ray from the camera passes through the box first (slab test)."""
    ray = points - CAMERA_IN_TABLE
    with np.errstate(divide="ignore", invalid="ignore"):
        t_low, t_high = (BOX_LOW - CAMERA_IN_TABLE) / ray, (BOX_HIGH - CAMERA_IN_TABLE) / ray
    enter = np.nanmax(np.minimum(t_low, t_high), axis=1)
    leave = np.nanmin(np.maximum(t_low, t_high), axis=1)
    return (enter < leave) & (enter < 1.0 - 1e-9) & (leave > 0.0)


def _box_faces(m: int, rng: np.random.Generator) -> np.ndarray:
    """(m, 3) table-frame points spread evenly over the box's three faces the camera sees."""
    a = rng.uniform(0.0, BOX_SIDE, (m, 2))
    face = rng.integers(0, 3, m)[:, None]
    top = BOX_LOW + np.column_stack([a, np.full(m, BOX_SIDE)])
    side_x = BOX_LOW + np.column_stack([np.zeros(m), a])
    side_y = BOX_LOW + np.column_stack([a[:, 0], np.full(m, BOX_SIDE), a[:, 1]])
    return np.where(face == 0, top, np.where(face == 1, side_x, side_y))


def tilted_table(n: int, rng: np.random.Generator, box: bool) -> np.ndarray:
    """(n, 3) points of a 1 m square plane tilted 20 degrees towards a camera 1 m away, with 2 mm noise,
    optionally with 15 % of the points on a 0.2 m box standing on it: only what the camera could see, the
    box's top and the two sides that face the camera, and the table less what the box hides."""
    on_box = int(0.15 * n) if box else 0
    table = np.empty((0, 3))
    while len(table) < n - on_box:  # the box hides a little of the table: draw until enough are seen
        uv = rng.uniform(-0.5, 0.5, (n - on_box, 2))
        drawn = np.column_stack([uv, np.zeros(len(uv))])
        table = np.vstack([table, drawn[~_hidden_by_box(drawn)] if box else drawn])
    points = np.vstack([table[:n - on_box], _box_faces(on_box, rng)]) @ R_CAMERA_TABLE.T + T_CAMERA_TABLE
    return points + rng.normal(0.0, 0.002, points.shape)


def sensor(width: int, height: int) -> CameraIntrinsics:
    """A Kinect-v1 field of view at another resolution."""
    f = KINECT_FX * width / KINECT_WIDTH
    return CameraIntrinsics(width=width, height=height, fx=f, fy=f, cx=(width - 1) / 2, cy=(height - 1) / 2)


def decompose_row(cloud: PointCloud) -> dict:
    start = time.perf_counter()
    result = decompose(cloud, DecomposeParams(), np.random.default_rng(0))
    ms = (time.perf_counter() - start) * 1e3
    start = time.perf_counter()
    peer = open3d_plane_loop(cloud)
    peer_ms = (time.perf_counter() - start) * 1e3
    return dict(points=int(cloud.valid_mask.sum()), primitives=len(result.primitives), ms=ms,
                sampled=result.stats.n_sampled, peer_planes=int(peer.max()) + 1, peer_ms=peer_ms)


def _row(scene: str, density: float, draws: list[dict]) -> dict:
    """One scene at one density over its seeded draws: counts per draw, medians of the rest."""
    row = dict(scene=scene, density=density, draws=len(draws))
    for key in ("primitives", "peer_planes"):
        row[key] = [d[key] for d in draws]
    for key in ("points", "sampled", "ms", "peer_ms", "recognize_ms"):
        if key in draws[0]:
            row[key] = float(np.median([d[key] for d in draws]))
    for key in ("found", "false", "instances"):
        if key in draws[0]:
            row[key] = int(sum(d[key] for d in draws))
    return row


def run(densities: list[float], draws: int, scenes: int) -> list[dict]:
    catalog, meshes, library, samples, diameters = catalog_library()
    recognizer = Recognizer(library, "psorr")
    rows = []
    with tqdm(total=len(densities) * (2 * draws + scenes), desc="clouds", file=sys.stderr) as bar:
        for box in (False, True):
            for density in densities:
                found = []
                for seed in range(draws):
                    found.append(decompose_row(PointCloud(tilted_table(int(density * 1e6),
                                                                       np.random.default_rng(seed), box))))
                    bar.update()
                rows.append(_row("table and box" if box else "table", density, found))
        for density in densities:
            found = []
            for seed in range(scenes):
                scene = clutter_scene(seed, catalog, meshes, sensor(*RESOLUTIONS[density]))
                draw = decompose_row(scene.cloud)
                start = time.perf_counter()
                detections = recognizer.recognize(scene.cloud, np.random.default_rng(0)).detections
                draw["recognize_ms"] = (time.perf_counter() - start) * 1e3
                draw["found"], draw["false"] = grade(scene, detections, catalog, samples, diameters)
                draw["instances"] = len(scene.instances)
                found.append(draw)
                bar.update()
            rows.append(_row("4 parts and an arm, rendered", density, found))
    return rows


def _counts(values: list[int]) -> str:
    return ", ".join(str(v) for v in values)


def report(rows: list[dict], out: Path) -> None:
    lines = ["The same scenes at several point densities, 1 core (medians over each row's draws)", "",
             "| scene | points | sampled | PSORR primitives (per draw) | decompose ms | Open3D planes | Open3D ms "
             "| found | false | recognize ms |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        found = f"{r['found']}/{r['instances']}" if "found" in r else ""
        rec = f"{r['recognize_ms']:.0f}" if "recognize_ms" in r else ""
        lines.append(f"| {r['scene']} | {r['points'] / 1e6:.2f}M | {r['sampled'] / 1e6:.2f}M | "
                     f"{_counts(r['primitives'])} | {r['ms']:.0f} | {_counts(r['peer_planes'])} | {r['peer_ms']:.0f} | "
                     f"{found} | {r.get('false', '')} | {rec} |")
    verdicts = []
    for scene in dict.fromkeys(r["scene"] for r in rows):
        counts = [sorted(r["primitives"]) for r in rows if r["scene"] == scene and r["density"] <= 3]
        same = all(c == counts[0] for c in counts)
        verdicts.append(f"{scene}: {'the same counts' if same else 'counts differ'} at 0.3M, 1M and 3M points")
    at_3m = [r["ms"] for r in rows if r["density"] == 3]
    if at_3m:
        verdicts.append(f"3M points decomposed in a median of at most {max(at_3m):.0f} ms "
                        f"({'met' if max(at_3m) < TARGET_3M_MS else 'MISSED'}: < {TARGET_3M_MS:.0f} ms)")
    recall = {r["density"]: (r["found"], r["false"]) for r in rows if "found" in r}
    if recall:
        verdicts.append("rendered scenes: " + ("the same finds and false detections at every resolution"
                                               if len(set(recall.values())) == 1 else
                                               "finds or false detections differ between resolutions"))
    lines += ["", *[f"- {v}" for v in verdicts]]
    write_report(out, "density", lines, {"rows": rows, "verdicts": verdicts})
    plot(rows, out / "density.png")


def plot(rows: list[dict], path: Path) -> None:
    """Decomposition time against points for each scene (PSORR and Open3D), and recall against points."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 3.8))
    for k, scene in enumerate(dict.fromkeys(r["scene"] for r in rows)):
        mine = [r for r in rows if r["scene"] == scene]
        points = [r["points"] / 1e6 for r in mine]
        left.plot(points, [r["ms"] for r in mine], "o-", color=f"C{k}", label=f"PSORR, {scene}")
        left.plot(points, [r["peer_ms"] for r in mine], "s--", color=f"C{k}", alpha=0.6, label=f"Open3D, {scene}")
        if "found" in mine[0]:
            right.plot(points, [r["found"] / r["instances"] for r in mine], "o-", color=f"C{k}", label="recall")
            right.plot(points, [r["false"] / r["draws"] for r in mine], "s--", color="C3", label="false / scene")
    left.axhline(TARGET_3M_MS, color="k", lw=0.8, ls=":")
    left.set(xscale="log", yscale="log", xlabel="points (millions)", ylabel="decomposition ms, 1 core")
    right.set(xscale="log", ylim=(0, 1.05), xlabel="points (millions)", title="rendered clutter, PSORR")
    left.legend(fontsize=7)
    right.legend(fontsize=8)
    for ax in (left, right):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--densities", default="0.3,1,3,10",
                        help=f"millions of points, from {sorted(RESOLUTIONS)}")
    parser.add_argument("--draws", type=int, default=3, help="noise draws of each sampled table scene")
    parser.add_argument("--scenes", type=int, default=6, help="seeded clutter scenes at each resolution")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    densities = [float(d) for d in args.densities.split(",")]
    unknown = [d for d in densities if d not in RESOLUTIONS]
    if unknown:
        parser.error(f"--densities: {unknown} not among {sorted(RESOLUTIONS)}")
    report(run(densities, args.draws, args.scenes), args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
