"""The paper's Table 1: PSORR against ORR on single parts, full and partial
views, at two resolutions, with the library trained on all 8 catalog parts.

Cases, per object (chassis, transformer, circuit_board) and seed:
- full view: an unorganised cloud of the whole posed model surface (evenly
  sampled, 1 mm Gaussian noise) standing on a noisy patch of table top, in
  the sensor frame of a camera 0.65-0.8 m above the table (the same seeded
  geometry as psorr.scenes);
- partial view: the seeded Kinect-v1 rendering of psorr.scenes.
Each at two resolutions: as is, and thinned to about a quarter of the points
(one point per voxel of twice the sampling spacing for the full view; every
2nd row and column for the organised partial view).

A run is recognised when a detection of the right model lies within a
symmetric ADD of 0.1 x the model's diameter. Prints a markdown table (counts
over seeds, medians over seeds) and a summary against the issue's target,
and writes benchmarks/results/table1.{md,json,png} (table1.quick.* with --quick).

    python benchmarks/table1.py [--seeds 3] [--quick] [--objects chassis,transformer] [--out DIR]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import sys
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import numpy as np
import trimesh
from scipy.spatial import Delaunay
from tqdm import tqdm

from psorr import ModelLibrary, Recognizer
from psorr.camera import look_at
from psorr.recognize import RecognizeParams
from psorr.scenes import workpiece_scene
from psorr.types import PointCloud
from psorr.workpieces import load_catalog, symmetric_add

ROOT = Path(__file__).resolve().parents[1]
OBJECTS = ("chassis", "transformer", "circuit_board")
METHODS = ("psorr", "orr")
ADD_THRESHOLD = 0.1          # x model diameter
FULL_SPACING = 0.0015        # m: full-view sampling, about a Kinect v1 pixel at 0.7-0.8 m
FULL_NOISE = 0.001           # m: Gaussian sigma of the full-view points
TABLE_PATCH = 0.4            # m: side of the table-top patch around the part in the full view
TARGET_HYP_RATIO = 1 / 20    # PSORR hypotheses <= this x ORR's
TARGET_VERIFY_SPEEDUP = 50.0  # ORR ms per hypothesis >= this x PSORR's


# ---------------------------------------------------------------- clouds


def _camera_and_pose(rng: np.random.Generator):
    """A part pose on the table (random yaw and place) and a camera as in psorr.scenes:
    0.65-0.8 m above the table, 20-30 deg from the vertical. Returns (T_world_model, T_world_camera)."""
    x, y, yaw = rng.uniform(-0.1, 0.1), rng.uniform(0.0, 0.2), rng.uniform(0, 2 * np.pi)
    T_world_model = trimesh.transformations.rotation_matrix(yaw, (0, 0, 1))
    T_world_model[:3, 3] = (x, y, 0.0)
    height, tilt = rng.uniform(0.65, 0.8), np.radians(rng.uniform(20.0, 30.0))
    target = np.array([0.0, 0.12, 0.0])
    return T_world_model, look_at(target + (0.0, -height * np.tan(tilt), height), target)


def _even_surface(mesh: trimesh.Trimesh, spacing: float, seed: int) -> np.ndarray:
    """About one point per spacing^2 of surface: random samples thinned so that no two
    are closer than 0.6 spacing (trimesh's rejection sampling keeps about a third of
    its draws at that radius, hence the draw count)."""
    count = int(3 * mesh.area / spacing**2)
    logger = logging.getLogger("trimesh.sample")
    level = logger.level
    logger.setLevel("ERROR")  # it warns whenever it keeps fewer than it drew, which is by design here
    try:
        points, _ = trimesh.sample.sample_surface_even(mesh, count, radius=0.6 * spacing, seed=seed)
    finally:
        logger.setLevel(level)
    return np.asarray(points)


def full_view(rng: np.random.Generator, mesh: trimesh.Trimesh):
    """(unorganised PointCloud in the camera frame, labels 0 table / 1 part, T_camera_model)."""
    T_world_model, T_world_camera = _camera_and_pose(rng)
    model_pts = _even_surface(mesh, FULL_SPACING, int(rng.integers(2**31)))
    world_model = model_pts @ T_world_model[:3, :3].T + T_world_model[:3, 3]
    # Table top: a jittered grid at the same spacing, minus the part's footprint (the part stands on it).
    half, n = TABLE_PATCH / 2, int(TABLE_PATCH / FULL_SPACING)
    gx, gy = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    table = np.column_stack([gx.ravel(), gy.ravel()]) * FULL_SPACING - half
    table += rng.uniform(0, FULL_SPACING, table.shape) + T_world_model[:2, 3]
    footprint = Delaunay(world_model[:, :2])
    table = table[footprint.find_simplex(table) < 0]
    world = np.vstack([world_model, np.column_stack([table, np.zeros(len(table))])])
    labels = np.concatenate([np.ones(len(world_model), np.int64), np.zeros(len(table), np.int64)])
    world += rng.normal(0.0, FULL_NOISE, world.shape)
    T_camera_world = np.linalg.inv(T_world_camera)
    points = world @ T_camera_world[:3, :3].T + T_camera_world[:3, 3]
    return PointCloud(points, labels=labels), T_camera_world @ T_world_model


def partial_view(rng: np.random.Generator, meshes: dict, name: str):
    """(organised Kinect-v1 PointCloud, T_camera_model) from psorr.scenes."""
    scene = workpiece_scene(rng, meshes, [name])
    return scene.cloud, scene.instances[0].T_camera_model


def _one_per_voxel(points: np.ndarray, voxel: float) -> np.ndarray:
    keys = np.floor(points / voxel).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    return np.sort(first)


def thin_voxel(cloud: PointCloud, spacing: float, fraction: float = 0.25) -> tuple[PointCloud, float]:
    """One point (the first) per voxel of an unorganised cloud, the voxel sized (by bisection) to
    keep about `fraction` of the points. A tilted surface cuts (|nx|+|ny|+|nz|) voxels per voxel
    face area, so a voxel of exactly 2x the spacing keeps ~40%, not 25%. Returns (cloud, voxel)."""
    pts = cloud.points[cloud.valid_mask]
    lo, hi = spacing, 5 * spacing
    for _ in range(14):
        voxel = (lo + hi) / 2
        keep = _one_per_voxel(pts, voxel)
        if abs(len(keep) / len(pts) - fraction) < 0.005:
            break
        lo, hi = (voxel, hi) if len(keep) / len(pts) > fraction else (lo, voxel)
    labels = None if cloud.labels is None else cloud.labels[cloud.valid_mask][keep]
    return PointCloud(pts[keep], labels=labels), voxel


def thin_organised(cloud: PointCloud) -> PointCloud:
    """Every 2nd row and column of an organised cloud."""
    h, w = cloud.height, cloud.width
    keep = (np.arange(h)[:, None] % 2 == 0) & (np.arange(w)[None, :] % 2 == 0)
    keep = keep.ravel()
    labels = None if cloud.labels is None else cloud.labels[keep]
    return PointCloud(cloud.points[keep], labels=labels, width=(w + 1) // 2, height=(h + 1) // 2)


# ---------------------------------------------------------------- scoring


def _symmetry_rotations(info) -> np.ndarray:
    """(K, 3, 3) rotations of the part's symmetries, with spins about a continuous axis if it has one."""
    rots = info.symmetries[:, :3, :3]
    if info.continuous_axis is not None:
        a = info.continuous_axis
        k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        ang = np.deg2rad(np.arange(0.0, 360.0, 1.0))
        spins = np.eye(3) + np.sin(ang)[:, None, None] * k + (1 - np.cos(ang))[:, None, None] * (k @ k)
        rots = np.einsum("kij,mjl->kmil", rots, spins).reshape(-1, 3, 3)
    return rots


def rotation_error_deg(T_est, T_true, info) -> float:
    """Degrees between the estimated and true rotation, minimised over the part's symmetries."""
    rel = np.einsum("ji,kjl->kil", T_est[:3, :3], T_true[:3, :3] @ _symmetry_rotations(info))
    cos = (np.trace(rel, axis1=1, axis2=2) - 1) / 2
    return float(np.degrees(np.arccos(np.clip(cos, -1, 1))).min())


def score(result, name: str, T_true, library, catalog) -> dict:
    """Recognised?, and ADD (mm) and rotation error (deg) of the best detection of the right model."""
    model, info = library.model(name), catalog[name]
    best = None
    for det in result.detections:
        if det.model != name:
            continue
        add = symmetric_add(model.points, det.T_cloud_model, T_true, info)
        if best is None or add < best[0]:
            best = (add, rotation_error_deg(det.T_cloud_model, T_true, info))
    wrong = sum(det.model != name for det in result.detections)
    if best is None:
        return dict(recognised=False, add_mm=None, rot_deg=None, wrong=wrong)
    return dict(recognised=bool(best[0] < ADD_THRESHOLD * model.diameter), add_mm=best[0] * 1e3,
                rot_deg=best[1], wrong=wrong)


# ---------------------------------------------------------------- running


def run(objects, views, seeds, library, catalog) -> list[dict]:
    meshes = {n: catalog[n].load_mesh() for n in catalog}
    recognizers = {m: Recognizer(library, method=m, params=RecognizeParams()) for m in METHODS}
    jobs = [(o, v, s) for o in objects for v in views for s in seeds]
    runs = []
    bar = tqdm(total=len(jobs) * 2 * len(METHODS), desc="table 1 runs", file=sys.stderr)
    for name, view, seed in jobs:
        rng = np.random.default_rng(seed)
        if view == "full":
            cloud, T_true = full_view(rng, meshes[name])
            thinned, _ = thin_voxel(cloud, FULL_SPACING)
        else:
            cloud, T_true = partial_view(rng, meshes, name)
            thinned = thin_organised(cloud)
        for resolution, c in (("full res", cloud), ("1/4 res", thinned)):
            n_points = int(c.valid_mask.sum())
            n_part = int((c.labels == 1).sum()) if c.labels is not None else -1
            for method in METHODS:
                bar.set_postfix_str(f"{name} {view} {resolution} {method} seed {seed}")
                result = recognizers[method].recognize(c, np.random.default_rng(seed))
                s = result.stats
                runs.append(dict(object=name, view=view, resolution=resolution, points=n_points,
                                 part_points=n_part, method=method, seed=seed, hypotheses=s.hypotheses,
                                 verify_ms_per_hypothesis=s.verify_ms_per_hypothesis,
                                 decomposition_ms=s.decomposition_ms, total_ms=s.total_ms,
                                 detections=[d.model for d in result.detections],
                                 **score(result, name, T_true, library, catalog)))
                bar.update()
    bar.close()
    return runs


def _median(values):
    values = [v for v in values if v is not None]
    return float(np.median(values)) if values else None


def _fmt(value, spec: str, empty: str = "-") -> str:
    return empty if value is None else format(value, spec)


def cells(runs) -> list[dict]:
    """One row per (object, view, resolution, method): counts and medians over the seeds."""
    keys = []
    for r in runs:
        k = (r["object"], r["view"], r["resolution"], r["method"])
        if k not in keys:
            keys.append(k)
    rows = []
    for k in keys:
        rs = [r for r in runs if (r["object"], r["view"], r["resolution"], r["method"]) == k]
        hit = [r for r in rs if r["recognised"]]
        rows.append(dict(
            object=k[0], view=k[1], resolution=k[2], method=k[3], n=len(rs),
            points=_median([r["points"] for r in rs]), part_points=_median([r["part_points"] for r in rs]),
            hypotheses=_median([r["hypotheses"] for r in rs]),
            # A run with no hypotheses has no verification time per hypothesis.
            verify_ms=_median([r["verify_ms_per_hypothesis"] for r in rs if r["hypotheses"] > 0]),
            recognised=len(hit), wrong=sum(r["wrong"] for r in rs),
            add_mm=_median([r["add_mm"] for r in hit]), rot_deg=_median([r["rot_deg"] for r in hit]),
            best_add_mm=_median([r["add_mm"] for r in rs]),
            total_ms=_median([r["total_ms"] for r in rs])))
    return rows


def table_markdown(rows) -> str:
    lines = ["| object | view | resolution (points / on the part) | algorithm | hypotheses | verify ms / hyp "
             "| recognised "
             "| ADD mm | rot err deg | wrong-model dets | total ms |",
             "|---|---|---|---|---:|---:|---|---:|---:|---:|---:|"]
    for r in rows:
        add = _fmt(r["add_mm"], ".1f")
        if r["add_mm"] is None and r["best_add_mm"] is not None:
            add = f"({r['best_add_mm']:.0f})"  # nearest detection of the right model, not within 0.1 d
        lines.append(
            f"| {r['object']} | {r['view']} | {r['resolution']} ({r['points']:.0f} / {r['part_points']:.0f}) "
            f"| {r['method']} "
            f"| {_fmt(r['hypotheses'], '.0f')} | {_fmt(r['verify_ms'], '.3f')} "
            f"| {'yes' if r['recognised'] == r['n'] else 'no' if r['recognised'] == 0 else 'partly'} "
            f"{r['recognised']}/{r['n']} | {add} | {_fmt(r['rot_deg'], '.1f')} | {r['wrong']} "
            f"| {_fmt(r['total_ms'], '.0f')} |")
    return "\n".join(lines)


def summary(runs, rows) -> tuple[str, dict]:
    """Ratios against the target, per case and over all runs."""
    by = {m: [r for r in runs if r["method"] == m] for m in METHODS}
    hyp = {m: sum(r["hypotheses"] for r in by[m]) for m in METHODS}
    # Verification time over all runs: total verify ms / total hypotheses.
    vms = {m: sum(r["verify_ms_per_hypothesis"] * r["hypotheses"] for r in by[m]) / max(hyp[m], 1) for m in METHODS}
    rec = {m: sum(r["recognised"] for r in by[m]) for m in METHODS}
    n = {m: len(by[m]) for m in METHODS}
    hyp_ratio = hyp["psorr"] / max(hyp["orr"], 1)
    speedup = vms["orr"] / vms["psorr"] if vms["psorr"] > 0 else None
    lines = ["| case | PSORR/ORR hypotheses | ORR/PSORR verify ms per hyp | recognised PSORR | recognised ORR |",
             "|---|---:|---:|---:|---:|"]
    cases_worse, cases_over, cases_none = [], [], []
    for p in [r for r in rows if r["method"] == "psorr"]:
        o = next(r for r in rows if r["method"] == "orr" and
                 (r["object"], r["view"], r["resolution"]) == (p["object"], p["view"], p["resolution"]))
        case = f"{p['object']} {p['view']} {p['resolution']}"
        hr = None if not o["hypotheses"] else p["hypotheses"] / o["hypotheses"]
        if hr is not None and hr > TARGET_HYP_RATIO:
            cases_over.append(f"{case} ({hr:.3f})")
        if not p["hypotheses"]:
            cases_none.append(case)
        sp = None if not p["verify_ms"] or o["verify_ms"] is None else o["verify_ms"] / p["verify_ms"]
        ratio = "0 (no pairs)" if not p["hypotheses"] else _fmt(hr, ".3f")
        lines.append(f"| {case} | {ratio} | {_fmt(sp, '.3f')} | {p['recognised']}/{p['n']} "
                     f"| {o['recognised']}/{o['n']} |")
        if p["recognised"] < o["recognised"]:
            cases_worse.append(case)
    lines.append(f"| **all runs** | **{hyp_ratio:.3f}** | **{_fmt(speedup, '.3f')}** "
                 f"| **{rec['psorr']}/{n['psorr']}** | **{rec['orr']}/{n['orr']}** |")
    met_hyp = hyp_ratio <= TARGET_HYP_RATIO
    met_speed = speedup is not None and speedup >= TARGET_VERIFY_SPEEDUP
    met_rec = rec["psorr"] >= rec["orr"] and not cases_worse
    verdict = [
        "",
        f"Target: PSORR uses <= 1/20 of ORR's hypotheses, >= {TARGET_VERIFY_SPEEDUP:.0f}x less verification "
        "time per hypothesis, at equal or better recognition.",
        f"- hypotheses: PSORR {hyp['psorr']} vs ORR {hyp['orr']} over all runs, ratio {hyp_ratio:.3f} "
        f"(target <= {TARGET_HYP_RATIO:.3f}): **{'met' if met_hyp else 'MISSED'}** over all runs"
        + (f"; per case above 1/20: {', '.join(cases_over)}" if cases_over else "; met in every case")
        + (f"; PSORR found no scene pairs at all (0 hypotheses) in: {', '.join(cases_none)}" if cases_none else ""),
        f"- verification ms per hypothesis: PSORR {vms['psorr']:.3f} vs ORR {vms['orr']:.3f}, ORR/PSORR = "
        f"{_fmt(speedup, '.3f')} (target >= {TARGET_VERIFY_SPEEDUP:.0f}): **{'met' if met_speed else 'MISSED'}**",
        f"- recognition: PSORR {rec['psorr']}/{n['psorr']}, ORR {rec['orr']}/{n['orr']}"
        + (f"; PSORR worse in: {', '.join(cases_worse)}" if cases_worse else "; PSORR never worse per case")
        + f": **{'met' if met_rec else 'MISSED'}**",
    ]
    return "\n".join(lines + verdict), dict(hypotheses_ratio=hyp_ratio, verify_speedup=speedup,
                                            recognised=rec, runs=n, met=dict(hypotheses=met_hyp,
                                                                             verification=met_speed,
                                                                             recognition=met_rec))


def _plot(rows, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    cases = [r for r in rows if r["method"] == "psorr"]
    labels = [f"{r['object'].replace('_', ' ')}\n{r['view']}, {r['resolution']}" for r in cases]
    x = np.arange(len(cases))
    width = 0.38
    fig, axes = plt.subplots(2, 1, figsize=(max(7, 1.15 * len(cases) + 2), 7.2), sharex=True)
    colors = {"psorr": "tab:blue", "orr": "tab:orange"}
    for ax, key, title in ((axes[0], "hypotheses", "hypotheses (median over seeds)"),
                           (axes[1], "verify_ms", "verification ms per hypothesis (median, 1 core)")):
        for i, method in enumerate(METHODS):
            mine = [next(r for r in rows if r["method"] == method and (r["object"], r["view"], r["resolution"])
                         == (c["object"], c["view"], c["resolution"])) for c in cases]
            vals = np.array([r[key] if r[key] else np.nan for r in mine], dtype=float)
            bars = ax.bar(x + (i - 0.5) * width, vals, width, color=colors[method], label=method)
            for b, r, v in zip(bars, mine, vals):
                text = f"{r['recognised']}/{r['n']}" if key == "hypotheses" else ""
                if np.isnan(v):
                    ax.text(b.get_x() + b.get_width() / 2, 0.03, "no hypotheses", ha="center", va="bottom",
                            fontsize=7, rotation=90, transform=ax.get_xaxis_transform())
                elif text:
                    ax.text(b.get_x() + b.get_width() / 2, v * 1.15, text, ha="center", va="bottom", fontsize=7)
        ax.set_yscale("log")
        ax.set_title(title, fontsize=10)
        ax.grid(axis="y", which="both", alpha=0.3)
    top = max((r["hypotheses"] or 1) for r in rows)
    axes[0].set_ylim(1, top * 5)
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="upper center", bbox_to_anchor=(0.5, 0.955), ncol=2, fontsize=8,
               frameon=False, title="bar labels above the hypotheses: recognised / seeds", title_fontsize=7.5)
    ms = [r["verify_ms"] for r in rows if r["verify_ms"]]
    if ms:  # whole decades, so the log bars have a common, readable base
        axes[1].set_ylim(10 ** np.floor(np.log10(min(ms))), 10 ** np.ceil(np.log10(max(ms)) + 0.3))
    for ax in axes:
        ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    axes[1].set_xticks(x, labels, fontsize=7.5)
    fig.suptitle("Table 1: PSORR vs ORR on single parts, library of all 8 catalog parts", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.92))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def source_fingerprint() -> str:
    """sha256 (12 hex) of the psorr sources, to tie a results file to the code that made it."""
    h = hashlib.sha256()
    for f in sorted((ROOT / "psorr").rglob("*.py")):
        h.update(f.relative_to(ROOT).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:12]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=3, help="seeds per case (default 3)")
    parser.add_argument("--quick", action="store_true",
                        help="one seed, partial view only; writes table1.quick.{md,json,png}")
    parser.add_argument("--objects", default=",".join(OBJECTS), help="comma-separated catalog parts")
    parser.add_argument("--views", default="full,partial", help="full, partial or both")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    seeds = [0] if args.quick else list(range(args.seeds))
    views = ["partial"] if args.quick else args.views.split(",")
    objects = args.objects.split(",")
    start = time.perf_counter()
    fingerprint = source_fingerprint()
    catalog = load_catalog()
    library = ModelLibrary.from_meshes([catalog[n].mesh_path for n in sorted(catalog)])
    print(f"library: {len(library)} models {library.names}, trained/loaded in {library.train_ms:.0f} ms",
          file=sys.stderr)
    runs = run(objects, views, seeds, library, catalog)
    rows = cells(runs)
    table = table_markdown(rows)
    text, ratios = summary(runs, rows)
    elapsed = time.perf_counter() - start
    if source_fingerprint() != fingerprint:
        print(f"note: psorr sources changed during the run; it used the version it imported at its start "
              f"({fingerprint})", file=sys.stderr)
    header = (f"psorr sources sha256 {fingerprint}. Seeds {seeds}, views {views}, {len(runs)} runs, "
              f"{elapsed:.0f} s wall on 1 core. "
              f"Counts are over seeds; hypotheses, ms and pose errors are medians over seeds (pose errors "
              f"over the recognised runs; in brackets, the nearest detection of the right model when none "
              f"was within 0.1 d). ORR draws up to RecognizeParams.orr_hypotheses = "
              f"{RecognizeParams().orr_hypotheses} hypotheses.")
    print(table)
    print()
    print(text)
    print(f"\nrun time {elapsed:.0f} s", file=sys.stderr)
    args.out.mkdir(parents=True, exist_ok=True)
    stem = "table1.quick" if args.quick else "table1"  # a quick check never overwrites the full table
    (args.out / f"{stem}.md").write_text(f"# Table 1 reproduction\n\n{header}\n\n{table}\n\n## Against the target"
                                        f"\n\n{text}\n")
    (args.out / f"{stem}.json").write_text(json.dumps(dict(psorr_sources_sha256=fingerprint, seeds=seeds, views=views,
                                                          elapsed_s=elapsed,
                                                          ratios=ratios, runs=runs), indent=1))
    _plot(rows, args.out / f"{stem}.png")
    print(f"wrote {args.out / stem}.md, .json and .png", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
