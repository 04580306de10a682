"""The `psorr-sim` command line.

`perceive` builds the seeded robot cell, renders the Kinect's noisy cloud,
recognises the workpieces with PSORR from their CAD meshes and grades each
recognised pose against the simulator's truth. It is the perception step of
a pick-and-place episode.

`run TASK.yaml` runs seeded pick-and-place episodes: each part is picked
with a catalog grasp and placed in its fixture, from the recognised poses or
the true ones (oracle), and judged on the simulator's truth. With the
occluder on, a person reaches over the table now and then; the robot sees
them in its camera, waits before looking again and stops while they reach.

`plan PLAN.yaml` checks a process plan against its cell, plans it with a STRIPS planner (or takes the
person's actions in it, once they reach the goal) and executes it, binding each symbolic object to a
part the robot recognises; a failed action is repaired by planning again.

`sweep SWEEP.yaml --out DIR` runs a grid of seeded episodes on a local process pool (or on Ray with
--ray), writing DIR/episodes.parquet and DIR/picks.parquet; a stopped sweep resumes where it left off.

`grasps TASK.yaml --out DIR` draws each part of a task as the cell builds it, with its grasps in each of
its most probable rests (the upright part's alone for a part placed upright): one PNG a part.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from psorr.cli import at_least_one, check_output, run_parsed, seed
from sim.modes import PoseSource, choices


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _perceive(args) -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from psorr.library.models import ModelLibrary
    from psorr.recognize import Recognizer
    from psorr.sensing.kinect_noise import KINECT_V1
    from psorr.synthetic.catalog import symmetric_add
    from psorr.viz.render import save_detections_png
    from sim.devices.sensor import DepthCamera
    from sim.episode import pose_error
    from sim.world import WorldConfig, build_world

    check_output(args.out, "--out")
    rng = np.random.default_rng(args.seed)
    config = WorldConfig(workpieces=tuple(args.parts)) if args.parts else WorldConfig()
    world = build_world(config, rng)
    _log(f"built the cell with {', '.join(world.workpieces)} (seed {args.seed})")
    with DepthCamera(world.model, world.camera_name) as camera:
        frame = camera.render(world.data, rng, KINECT_V1)
    library = ModelLibrary.from_meshes([world.catalog[name].mesh_path for name in sorted(world.catalog)])
    result = Recognizer(library).recognize(frame.cloud, rng)
    T_camera_world = np.linalg.inv(frame.T_world_camera)
    rows, found = [], set()
    for det in result.detections:
        info, model = world.catalog[det.model], library.model(det.model)
        T_true = T_camera_world @ world.body_pose(det.model) if det.model in world.workpieces else None
        add = symmetric_add(model.points[::10], det.T_cloud_model, T_true, info) if T_true is not None else np.inf
        pos, rot = pose_error(det.T_cloud_model, T_true, info) if T_true is not None else (np.inf, np.inf)
        ok = add < 0.1 * model.diameter
        found |= {det.model} if ok else set()
        rows.append({"model": det.model, "score": det.score, "pos_mm": pos, "rot_deg": rot, "add_mm": add * 1e3,
                     "correct": ok})
    missed = [name for name in world.workpieces if name not in found]
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        plt.imsave(out / "rgb.png", frame.rgb)
        save_detections_png(out / "recognition.png", frame.cloud, result.detections, library)
        _log(f"wrote {out / 'rgb.png'} and {out / 'recognition.png'}")
    if args.json:
        print(json.dumps({"parts": list(world.workpieces), "detections": rows, "missed": missed,
                          "total_ms": result.stats.total_ms}))
        return 0
    # The verdict is ADD's (the mean model-point distance, under 0.1 diameter), so it is shown beside them.
    print(f"{'detection':<15} {'score':>5} {'pos err mm':>10} {'rot err deg':>11} {'ADD mm':>7}  verdict")
    for r in rows:
        print(f"{r['model']:<15} {r['score']:>5.2f} {r['pos_mm']:>10.1f} {r['rot_deg']:>11.1f} {r['add_mm']:>7.1f}  "
              f"{'correct' if r['correct'] else 'WRONG'}")
    print(f"found {len(found)} of {len(world.workpieces)} parts in {result.stats.total_ms:.0f} ms; "
          f"missed: {', '.join(missed) or 'none'}")
    return 0


def _run(args) -> int:
    from tqdm import tqdm

    from sim.control.recorder_hooks import combined
    from sim.episode import run_episode
    from sim.world import build_world
    from sim.world.tasks import load_task

    task = load_task(args.task)
    occluder = args.occluder == "on"
    results, rows = [], []
    for episode in tqdm(range(args.episodes), desc=f"episodes ({args.poses}, occluder {args.occluder})",
                        file=sys.stderr):
        rng = np.random.default_rng([args.seed, episode])
        world = build_world(task.world, rng)
        recorder = rerun = None
        if args.record:
            from sim.recording.recorder import EpisodeRecorder

            recorder = EpisodeRecorder(Path(args.record), f"episode_{args.seed}_{episode}")
        if args.rerun is not None:
            from sim.recording.rerun_episode import recorder_for_option

            rerun = recorder_for_option(args.rerun, episode if args.episodes > 1 else None)
        try:
            result = run_episode(world, rng, poses=args.poses, occluder=occluder, recorder=combined(recorder, rerun))
        finally:  # an unfinished MP4 would leave its ffmpeg process running
            if recorder is not None:
                for path in recorder.close():
                    _log(f"wrote {path}")
            if rerun is not None:
                rerun.close()
        results.append(result)
        rows += [(episode, p) for p in result.picks]
    summary = summarize(results, args.episodes)
    if args.json:
        print(json.dumps(summary))
        return 0
    # Catalog grasp names run to 16 characters ("outer_limb_pos_x"); the column takes the longest shown.
    width = max([14] + [len(p.grasp_name or "-") for _, p in rows])
    print(f"{'ep':>3} {'part':<15} {'grasp':<{width}} {'grasped':>7} {'lift m':>6} {'placed':>6} "
          f"{'pose err mm':>11} {'rot err deg':>11} {'looks':>5}  note")
    for episode, p in rows:
        print(f"{episode:>3} {p.part:<15} {p.grasp_name or '-':<{width}} {str(p.grasped):>7} {p.lifted_m:>6.3f} "
              f"{str(p.placed):>6} {p.pose_error_mm:>11.1f} {p.rot_error_deg:>11.1f} {p.looks:>5}  {p.note}")
    print(f"\n{summary['picks']} picks in {args.episodes} episodes ({args.poses} poses, occluder {args.occluder}): "
          f"grasp success {summary['grasp_success_rate']:.0%}, place success {summary['place_success_rate']:.0%}, "
          f"{summary['wall_s_per_episode']:.1f} s per episode")
    if occluder:
        stops = sum(r.protective_stops for r in results)
        waits = sum(r.occupied_looks for r in results)
        clearance = min(r.min_human_clearance_mm for r in results)
        print(f"the person reached in: {waits} looks waited, {stops} protective stops "
              f"({sum(r.stopped_s for r in results):.1f} s held); closest the arm came to them: {clearance:.0f} mm")
    return 0


def _plan(args) -> int:
    from sim.plans import goal_places, load_plan, run_plan, write_pddl

    plan = load_plan(args.plan)
    if args.pddl:
        for path in write_pddl(goal_places(plan), check_output(args.pddl, "--pddl")):
            _log(f"wrote {path}")
    result = run_plan(plan, np.random.default_rng(args.seed), poses=args.poses, occluder=args.occluder == "on")
    if args.json:
        print(json.dumps(result.as_json()))
        return 0
    print(f"{'action':<7} {'object':<22} {'destination':<11} outcome")
    for a in result.actions:
        print(f"{a.action:<7} {a.object:<22} {a.destination or '-':<11} {a.outcome}")
    print(f"\ngoal {'reached' if result.goal_reached else 'NOT reached'} with {result.replans} replans in "
          f"{result.wall_s:.1f} s ({args.poses} poses, occluder {args.occluder})")
    return 0


def _sweep(args) -> int:
    from tqdm import tqdm

    from sim.sweeps import gather, load_sweep, pending, run_local, run_ray
    from sim.sweeps.report import save_plot, summary_rows, summary_table

    sweep = load_sweep(args.sweep)
    out = check_output(args.out, "--out")
    todo = pending(sweep, out)
    _log(f"{len(sweep.episodes)} episodes in the grid, {len(sweep.episodes) - len(todo)} already in {out}")
    with tqdm(total=len(todo), desc="sweep", file=sys.stderr) as bar:
        if args.ray is not None:
            run_ray(todo, out, args.ray or None, done=lambda row: bar.update())
        else:
            run_local(todo, out, args.workers, done=lambda row: bar.update())
    episodes_path, picks_path = gather(sweep, out)
    import pyarrow.parquet as pq

    rows = summary_rows(pq.read_table(episodes_path), sweep.swept)
    print(summary_table(rows))
    picture = save_plot(rows, out / "grasp_success.png")
    _log(f"wrote {episodes_path}, {picks_path} and {picture}")
    return 0


def _grasps(args) -> int:
    from sim.recording.grasp_pictures import save_grasp_picture
    from sim.world.parts import cell_parts
    from sim.world.tasks import load_task

    out = check_output(args.out, "--out")
    task = load_task(args.task)
    for name, part in cell_parts(task.world, progress=_log).items():
        picture = save_grasp_picture(out / f"{name}.png", name, part.info.load_mesh(), part.grasps,
                                     color=part.info.color)
        print(f"wrote {picture.path}: {picture.summary}")
    return 0


def summarize(results, episodes: int) -> dict:
    """The `run --json` summary of :class:`sim.episode.EpisodeResult` s (rates over all picks)."""
    picks = [p for r in results for p in r.picks]
    recognised = [p for p in picks if np.isfinite(p.pose_error_mm)]
    return {
        "episodes": episodes,
        "picks": len(picks),
        "grasp_success_rate": float(np.mean([p.grasped for p in picks])) if picks else 0.0,
        "place_success_rate": float(np.mean([p.placed for p in picks])) if picks else 0.0,
        "pose_error_mm_median": float(np.median([p.pose_error_mm for p in recognised])) if recognised else None,
        "rot_error_deg_median": float(np.median([p.rot_error_deg for p in recognised])) if recognised else None,
        "wall_s_per_episode": float(np.mean([r.wall_s for r in results])) if results else 0.0,
    }


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="psorr-sim", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    per = sub.add_parser("perceive", help="render the cell's Kinect cloud and recognise the parts in it")
    per.add_argument("--seed", type=seed, default=0, help="seed of the layout and the sensor noise")
    per.add_argument("--parts", nargs="+", metavar="NAME", help="catalog parts to place (default: four)")
    per.add_argument("--out", metavar="DIR", help="write rgb.png and recognition.png here")
    per.add_argument("--json", action="store_true", help="print one JSON line instead of a table")
    per.set_defaults(run=_perceive)
    run = sub.add_parser("run", help="run seeded pick-and-place episodes of a task")
    run.add_argument("task", metavar="TASK.yaml", help="task file, e.g. tasks/demo.yaml")
    run.add_argument("--episodes", type=at_least_one, default=1, help="how many seeded episodes (default 1)")
    run.add_argument("--seed", type=seed, default=0)
    run.add_argument("--poses", choices=choices(PoseSource), default=PoseSource.RECOGNIZED.value,
                     help="grasp from the recognizer's poses (default) or the true ones")
    run.add_argument("--occluder", choices=("on", "off"), default="on",
                     help="a person reaches over the table now and then (default on); the robot waits for them")
    run.add_argument("--record", metavar="DIR",
                     help="write each episode's MP4 and a PNG contact sheet (views, recognised poses, grasps) here")
    run.add_argument("--rerun", nargs="?", const="", metavar="OUT.rrd",
                     help="record each episode for the Rerun viewer (OUT_<episode>.rrd for several; without a file: "
                          "stream to a viewer spawned now); needs pip install 'psorr[viz]'")
    run.add_argument("--json", action="store_true", help="print one JSON line of summary figures")
    run.set_defaults(run=_run)
    plan = sub.add_parser("plan", help="plan and execute a process plan, binding its objects to recognised parts")
    plan.add_argument("plan", metavar="PLAN.yaml", help="plan file, e.g. tasks/plans/kit.yaml")
    plan.add_argument("--seed", type=seed, default=0)
    plan.add_argument("--poses", choices=choices(PoseSource), default=PoseSource.RECOGNIZED.value,
                      help="grasp from the recognizer's poses (default) or the true ones")
    plan.add_argument("--occluder", choices=("on", "off"), default="on",
                      help="a person reaches over the table now and then (default on)")
    plan.add_argument("--pddl", metavar="DIR", help="also write the domain and problem as DIR/domain.pddl and "
                      "DIR/problem.pddl")
    plan.add_argument("--json", action="store_true", help="print one JSON line: goal_reached, actions, replans, "
                      "wall_s")
    plan.set_defaults(run=_plan)
    sweep = sub.add_parser("sweep", help="run a grid of seeded episodes to Parquet, locally or on Ray")
    sweep.add_argument("sweep", metavar="SWEEP.yaml", help="sweep file, e.g. tasks/sweeps/smoke.yaml")
    sweep.add_argument("--out", metavar="DIR", required=True, help="write the rows and the summary here; "
                       "a sweep started again with the same DIR resumes")
    sweep.add_argument("--workers", type=at_least_one, default=2, help="local processes (default 2)")
    sweep.add_argument("--ray", nargs="?", const="", default=None, metavar="ADDRESS",
                       help="run each episode as a Ray task: a local Ray instance, or the cluster at ADDRESS")
    sweep.set_defaults(run=_sweep)
    grasps = sub.add_parser("grasps", help="draw each part of a task with its grasps, a PNG per part")
    grasps.add_argument("task", metavar="TASK.yaml", help="task file, e.g. tasks/printed_parts.yaml")
    grasps.add_argument("--out", metavar="DIR", required=True,
                        help="write <part>.png here, a panel per rest (the 4 most probable with grasps)")
    grasps.set_defaults(run=_grasps)
    return parser


def main(argv: list[str] | None = None) -> int:
    return run_parsed(build_parser(), argv)


if __name__ == "__main__":
    sys.exit(main())
