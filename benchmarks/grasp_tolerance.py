"""How accurate must a pose estimate be for the gripper to pick a part and seat it in its fixture?

For every catalog part, in seeded one-part cells (no human), the simulator's true pose is perturbed
by a known error and handed to ``sim.skills.pick.pick_and_place`` as the estimate; the pick is judged on
the simulator's truth. Errors (one kind at a time, the part's origin is the centre of its resting face):

- translation: 2-20 mm in the table plane, along the part's own +x, +y, -x and -y axes;
- yaw: 1-12 deg about the vertical through the part's origin, both signs (skipped for parts with a
  continuous symmetry about the vertical: their yaw error is zero by definition);
- tilt: 2-15 deg about the part's horizontal x and y axes through its origin, both signs.

Each trial resets the cell to its home keyframe (which restores the part's settled pose), so trials
are independent; picks are deterministic, so there are no repeats, only directions and layouts.
"grasped" = both pads on the part and it lifted 5 cm and survived the transport; "placed" = seated
within 5 mm and 3 deg of its fixture (the pocket leaves 4 mm per side), resting on the table.

Reading the result: the first table gives success rates per error level over all parts, directions
and layouts (level 0 is the oracle pose, shared by all sweeps); translation is also split by the
direction relative to the gripper's closing axis, since the closing pads re-centre a part along that
axis but not across it. The second table gives, per part, the largest level at which it (and every
smaller level) still succeeded in >= 90% of trials: the recognizer's pose error has to stay below that.

    python benchmarks/grasp_tolerance.py [--quick] [--parts chassis bushing] [--seed 0]
writes benchmarks/results/grasp_tolerance.{md,json,png} (grasp_tolerance.quick.* with --quick).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import numpy as np
from scipy.spatial.transform import Rotation
from tqdm import tqdm

from psorr.errors import PsorrError
from psorr.synthetic.catalog import load_catalog
from sim.skills.grasps import grasp_named
from sim.skills.judging import PLACE_TOL_DEG, PLACE_TOL_MM
from sim.skills.pick import pick_and_place
from sim.world import WorldConfig, build_world

ROOT = Path(__file__).resolve().parents[1]
FULL = dict(translation=(0, 2, 4, 6, 8, 10, 15, 20), yaw=(0, 1, 2, 3, 5, 8, 12), tilt=(0, 2, 5, 10, 15),
            directions=4, layouts=2)
QUICK = dict(translation=(0, 4, 10, 20), yaw=(0, 3, 12), tilt=(0, 5), directions=4, layouts=1)
QUICK_PARTS = ("chassis", "transformer", "bushing")
SWEEPS = {"translation": "mm", "yaw": "deg", "tilt": "deg"}
RELIABLE = 0.9  # a level "holds" when at least this fraction of its trials succeeded


def yaw_symmetric(info) -> bool:
    axis = info.continuous_axis
    return axis is not None and abs(abs(float(axis[2])) - 1.0) < 1e-6


def perturbations(T: np.ndarray, info, grid: dict):
    """(sweep, level, direction in the part frame (deg, or sign), estimate (4, 4)) for one true pose ``T``."""
    R, p = T[:3, :3], T[:3, 3]

    def horizontal(angle_deg: float) -> np.ndarray:
        a = math.radians(angle_deg)
        d = R @ np.array([math.cos(a), math.sin(a), 0.0])
        d[2] = 0.0
        return d / np.linalg.norm(d)

    yield "zero", 0, "", np.array(T)
    for angle in np.arange(grid["directions"]) * 360.0 / grid["directions"]:
        d = horizontal(angle)
        for mm in grid["translation"][1:]:
            T_est = np.array(T)
            T_est[:3, 3] = p + d * mm * 1e-3
            yield "translation", mm, f"{angle:.0f}", T_est
    for deg in grid["yaw"][1:] if not yaw_symmetric(info) else ():
        for sign in (1, -1):
            T_est = np.array(T)
            T_est[:3, :3] = Rotation.from_rotvec([0.0, 0.0, math.radians(sign * deg)]).as_matrix() @ R
            yield "yaw", deg, f"{sign:+d}", T_est
    for angle in (0, 90, 180, 270):
        axis = horizontal(angle)
        for deg in grid["tilt"][1:]:
            T_est = np.array(T)
            T_est[:3, :3] = Rotation.from_rotvec(axis * math.radians(deg)).as_matrix() @ R
            yield "tilt", deg, f"{angle}", T_est


def relative_to_closing(trial: dict, info) -> str:
    """Whether a translation trial's direction ran along, across or diagonal to the executed grasp's closing axis."""
    if not trial["grasp"]:
        return "no grasp"
    c = np.asarray(grasp_named(info.name, trial["grasp"]).closing, float)[:2]
    a = math.radians(float(trial["direction"]))
    cos = abs(float(np.dot(c / np.linalg.norm(c), (math.cos(a), math.sin(a)))))
    return "along" if cos > 0.9 else "across" if cos < 0.1 else "diagonal"


def run(parts, grid, seed: int, catalog) -> list[dict]:
    names = sorted(catalog)
    eye = np.eye(4)
    total = grid["layouts"] * sum(len(list(perturbations(eye, catalog[p], grid))) for p in parts)
    trials, bar = [], tqdm(total=total, desc="picks", file=sys.stderr)
    for part in parts:
        info = catalog[part]
        for layout in range(grid["layouts"]):
            world_seed = [seed, names.index(part), layout]  # a part's layouts do not depend on --parts
            world = build_world(WorldConfig(workpieces=(part,), occluder=False), np.random.default_rng(world_seed))
            world.reset()
            T_true = world.body_pose(part)
            for sweep, level, direction, T_est in perturbations(T_true, info, grid):
                bar.set_postfix_str(f"{part} layout {layout} {sweep} {level}")
                world.reset()
                start = time.perf_counter()
                try:
                    r = pick_and_place(world, part, T_est)
                except PsorrError as exc:  # recorded, not fatal: one odd pick must not lose the run
                    r = None
                    note = f"error: {type(exc).__name__}: {exc}"
                trial = dict(part=part, layout=layout, world_seed=world_seed, sweep=sweep, level=level,
                             direction=direction, wall_s=time.perf_counter() - start)
                if r is None:
                    trial.update(grasp="", grasped=False, placed=False, note=note)
                else:
                    trial.update(grasp=r.grasp_name, grasped=r.grasped, placed=r.placed, lifted_m=r.lifted_m,
                                 place_error_mm=r.place_error_mm, place_error_deg=r.place_error_deg,
                                 pose_error_mm=r.pose_error_mm, rot_error_deg=r.rot_error_deg, note=r.note)
                if sweep == "translation":
                    trial["vs_closing"] = relative_to_closing(trial, info)
                trials.append(trial)
                bar.update()
    bar.close()
    return trials


def in_sweep(trials, sweep: str) -> list[dict]:
    """The sweep's trials plus the zero-error ones (level 0) of the parts it ran on."""
    ran = {t["part"] for t in trials if t["sweep"] == sweep}
    return [t for t in trials if t["sweep"] == sweep or (t["sweep"] == "zero" and t["part"] in ran)]


def rate(trials, key: str) -> float:
    return sum(t[key] for t in trials) / len(trials) if trials else math.nan


def holds_to(trials, levels, key: str):
    """Largest level with rate >= RELIABLE at it and every smaller level; None if level 0 already fails."""
    best = None
    for level in levels:
        if rate([t for t in trials if t["level"] == level], key) < RELIABLE:
            break
        best = level
    return best


def _frac(trials, key: str) -> str:
    k = sum(t[key] for t in trials)
    return f"{k}/{len(trials)} = {k / len(trials):.2f}" if trials else "-"


def tables(trials, grid, parts) -> str:
    lines = ["| sweep | error | trials | grasped | placed | placed, error along closing | placed, across closing |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for sweep, unit in SWEEPS.items():
        sel = in_sweep(trials, sweep)
        for level in grid[sweep]:
            at = [t for t in sel if t["level"] == level]
            split = ["-", "-"]
            if sweep == "translation" and level > 0:
                split = [_frac([t for t in at if t["vs_closing"] == side], "placed") for side in ("along", "across")]
            lines.append(f"| {sweep} | {level} {unit} | {len(at)} | {_frac(at, 'grasped')} | {_frac(at, 'placed')} "
                         f"| {split[0]} | {split[1]} |")
    overall = []
    for sweep, unit in SWEEPS.items():
        sel = in_sweep(trials, sweep)
        g, p = holds_to(sel, grid[sweep], "grasped"), holds_to(sel, grid[sweep], "placed")
        overall.append(f"{sweep}: grasps hold to {_level(g, grid[sweep], unit)}, "
                       f"places to {_level(p, grid[sweep], unit)}")
    lines += ["", f"Over all parts (>= {RELIABLE:.0%} of trials at that level and every smaller one): "
              + "; ".join(overall) + ".", "",
              f"Per part: the largest error that still succeeded in >= {RELIABLE:.0%} of its trials "
              "(and at every smaller level), grasp / place.", "",
              "| part | grasp at 0 | placed at 0 (place error) | translation | yaw | tilt |",
              "|---|---|---|---|---|---|"]
    for part in parts:
        mine = [t for t in trials if t["part"] == part]
        zero = [t for t in mine if t["sweep"] == "zero"]
        errs = ", ".join(f"{t['place_error_mm']:.1f} mm / {t['place_error_deg']:.1f} deg" if t["grasped"] else "-"
                         for t in zero)
        cells = []
        for sweep, unit in SWEEPS.items():
            sel = in_sweep(mine, sweep)
            if not any(t["sweep"] == sweep for t in sel):
                cells.append("n/a (symmetric)")
                continue
            g, p = holds_to(sel, grid[sweep], "grasped"), holds_to(sel, grid[sweep], "placed")
            cells.append(f"{_level(g, grid[sweep], unit)} / {_level(p, grid[sweep], unit)}")
        grasps = sorted({t["grasp"] or "none" for t in zero})
        lines.append(f"| {part} | {', '.join(grasps)} | {_frac(zero, 'placed')} ({errs}) | {' | '.join(cells)} |")
    failed = [t for t in trials if t["sweep"] == "zero" and not t["placed"]]
    if failed:
        lines += ["", "Failures at zero error:"] + [f"- {t['part']} layout {t['layout']}: {t['note']}" for t in failed]
    return "\n".join(lines)


def _level(level, levels, unit: str) -> str:
    if level is None:
        return "fails at 0"
    return f">= {level} {unit}" if level == levels[-1] else f"{level} {unit}"


def plot(trials, grid, parts, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
    for ax, (sweep, unit) in zip(axes, SWEEPS.items()):
        sel, levels = in_sweep(trials, sweep), grid[sweep]
        for k, part in enumerate(p for p in parts if any(t["part"] == p and t["sweep"] == sweep for t in sel)):
            ys = [rate([t for t in sel if t["part"] == part and t["level"] == v], "placed") for v in levels]
            ax.plot(levels, ys, color="gray", lw=0.8, alpha=0.35, label="place, per part" if k == 0 else None)
        for key, color in (("grasped", "C0"), ("placed", "C1")):
            ys = [rate([t for t in sel if t["level"] == v], key) for v in levels]
            ax.plot(levels, ys, "o-", color=color, lw=2, label=f"{key}, all parts")
        if sweep == "translation":
            for side, style in (("along", "--"), ("across", ":")):
                ys = [rate([t for t in sel if t["level"] == v and (v == 0 or t["vs_closing"] == side)], "placed")
                      for v in levels]
                ax.plot(levels, ys, style, color="C1", lw=1.2, label=f"placed, error {side} closing axis")
            clearance = WorldConfig().fixture_clearance * 1e3
            ax.axvline(clearance, color="k", lw=0.6, ls="-.", label=f"fixture clearance per side {clearance:g} mm")
        ax.set_xlabel(f"{sweep} error of the estimate ({unit})")
        ax.set_title({"translation": "in the table plane", "yaw": "about the vertical",
                      "tilt": "about a horizontal axis"}[sweep], fontsize=10)
        ax.set_ylim(-0.03, 1.03)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    axes[0].set_ylabel("success rate")
    fig.suptitle("Grasp and place success against injected pose error (oracle pose + known error)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def source_fingerprint() -> str:
    h = hashlib.sha256()
    for f in sorted([*(ROOT / "sim").rglob("*.py"), *(ROOT / "psorr").rglob("*.py")]):
        h.update(f.relative_to(ROOT).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:12]


def _clean(value):
    """NaN -> None, so the JSON is strict."""
    return None if isinstance(value, float) and math.isnan(value) else value


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer levels, directions and parts; writes *.quick.*")
    parser.add_argument("--parts", nargs="+", metavar="NAME", help="catalog parts (default: all 8)")
    parser.add_argument("--seed", type=int, default=0, help="seeds the cells' layouts (default 0)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    catalog = load_catalog()
    grid = QUICK if args.quick else FULL
    parts = args.parts or (list(QUICK_PARTS) if args.quick else sorted(catalog))
    unknown = [p for p in parts if p not in catalog]
    if unknown:
        parser.error(f"unknown parts {unknown}; choose from {sorted(catalog)}")
    fingerprint, start = source_fingerprint(), time.perf_counter()
    trials = run(parts, grid, args.seed, catalog)
    elapsed = time.perf_counter() - start
    if source_fingerprint() != fingerprint:
        print("note: sim/psorr sources changed during the run; it used the version it imported", file=sys.stderr)
    text = tables(trials, grid, parts)
    header = (f"sim+psorr sources sha256 {fingerprint}. Seed {args.seed}: {grid['layouts']} seeded one-part "
              f"layout(s) per part, {grid['directions']} translation directions, {len(trials)} picks, "
              f"{elapsed:.0f} s wall on 1 core. Placed = within {PLACE_TOL_MM:g} mm and {PLACE_TOL_DEG:g} deg of "
              f"the fixture, resting on the table. Translation rows split by the executed grasp's closing axis.")
    print(text)
    print(f"\n{len(trials)} picks in {elapsed:.0f} s wall ({elapsed / len(trials):.2f} s per pick)", file=sys.stderr)
    args.out.mkdir(parents=True, exist_ok=True)
    stem = str(args.out / ("grasp_tolerance.quick" if args.quick else "grasp_tolerance"))
    Path(f"{stem}.md").write_text(f"# Grasp and place tolerance to pose error\n\n{header}\n\n{text}\n")
    Path(f"{stem}.json").write_text(json.dumps(dict(
        sources_sha256=fingerprint, seed=args.seed, parts=parts, grid=grid, reliable=RELIABLE, elapsed_s=elapsed,
        trials=[{k: _clean(v) for k, v in t.items()} for t in trials]), indent=1))
    plot(trials, grid, parts, Path(f"{stem}.png"))
    print(f"wrote {stem}.md, .json and .png", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
