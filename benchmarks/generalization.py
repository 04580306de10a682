"""Recognising parts we have never seen: PSORR, ORR and three peers on seeded scenes of real CAD parts.

The parts are the Prusa i3 MK3's printed parts (../shared/cad/prusa_i3, millimetres) at least 25 mm
long, split into a dev and a test half (generalization_parts.py; tune on dev only). Each half's
library is all its parts. Scenes (psorr.synthetic.mesh_scenes): each part alone, in its stable resting
poses; clutter of 3-5 library parts with 1-3 distractors (parts of the other half, or simple shapes);
and the same with an arm-sized capsule across the view. Kinect v1 noise, 640x480, cameras 0.6-1.0 m
from the table, tilted 0-45 degrees (--camera-distance and --camera-tilt set another cell's).

A detection finds an instance within a symmetry-aware ADD of 0.1 x the model's diameter, the
symmetries found from the mesh (psorr.synthetic.mesh_symmetry); any other detection is false. Methods:
psorr and orr (psorr.Recognizer), o3d_global (Open3D's global registration tutorial per model,
peer_o3d_global.py), fpfh (cluster-wise FPFH, peer_fpfh.py) and opencv_ppf (peer_opencv.py; skipped
without OpenCV's contrib modules). Every method runs on one core, on a scene before the next scene.
Each model of the half is also trained once more alone, from its mesh file with the cache off, and
timed: a user's first run.

    python benchmarks/generalization.py [--split dev|test|both|all] [--quick] [--note "what else ran"]
    python benchmarks/generalization.py --cad MY_PARTS --units m     # your own parts, any mesh format
    python benchmarks/generalization.py --camera-distance 1.0 1.4 --camera-tilt 30 60   # your cell's camera

Any other folder of meshes is split into halves the same way on every machine (generalization_parts.py:
folder_split), or taken whole with --split all; its results are written as generalization-FOLDER.*, beside
the published ones, not over them, and so are those of another camera (generalization-camera-....*).

With --methods naming some of the methods, a half whose scenes are those of the results already
written keeps the other methods' rows from them, so that a change to one recognizer reruns only it.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import generalization_parts as gp
import numpy as np
from generalization_parts import HALVES, SplitError, checked_split, class_row, grade, left_open, nearest_add, part_info
from generalization_plot import drawn_scene, plot, sketch
from generalization_report import report
from tqdm import tqdm

from psorr.errors import PsorrError
from psorr.io.meshes import MESH_SUFFIXES, UNITS
from psorr.synthetic.mesh_scenes import SceneKind, SceneParams, load_meshes, mesh_scene, simple_shapes

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CAD = ROOT.parent / "shared" / "cad" / "prusa_i3"
METHODS = ("psorr", "orr", "o3d_global", "fpfh", "opencv_ppf")
SPLIT_SEED = {"dev": 1, "test": 2, "all": 3}
KIND_SEED = {SceneKind.SINGLE: 0, SceneKind.CLUTTER: 1, SceneKind.OCCLUDED: 2}


def _arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--split", choices=("dev", "test", "both", "all"), default="both",
                        help="a half of the parts (see generalization_parts.py), both halves, or all parts as one")
    parser.add_argument("--quick", action="store_true", help="4 single scenes, 1 clutter, 1 occluded a half; "
                        "writes generalization.quick.* (never a published result)")
    parser.add_argument("--singles", type=int, default=2, help="single-part scenes per part")
    parser.add_argument("--clutter", type=int, default=10, help="clutter scenes a half")
    parser.add_argument("--occluded", type=int, default=10, help="occluded clutter scenes a half")
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--cad", type=Path, help=f"the parts' folder (default: {DEFAULT_CAD})")
    parser.add_argument("--units", default="mm", choices=tuple(UNITS), help="the meshes' length unit")
    parser.add_argument("--min-length", type=float, default=gp.MIN_LENGTH * 1e3, metavar="MM",
                        help="parts shorter than this (the longest side of their bounding box) are left out; the "
                             "issue's benchmark: 25 mm (a Kinect-class sensor shows little of less)")
    parser.add_argument("--camera-distance", type=float, nargs=2, metavar=("NEAR", "FAR"),
                        default=SceneParams().camera_distance,
                        help="the camera's distance from the table point it looks at, metres (default: 0.6 1.0)")
    parser.add_argument("--camera-tilt", type=float, nargs=2, metavar=("LEAST", "MOST"),
                        default=SceneParams().camera_tilt_deg,
                        help="its line of sight from the vertical, degrees (default: 0 45)")
    parser.add_argument("--note", default="", help="what else ran on the machine, for the record")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    parser.add_argument("--report-only", action="store_true",
                        help="write the report and picture again from the results JSON, recognising nothing")
    args = parser.parse_args(argv)
    unknown = sorted(set(args.methods.split(",")) - set(METHODS))
    if unknown:
        parser.error(f"unknown methods {unknown}; choose from {', '.join(METHODS)}")
    if not args.min_length > 0:
        parser.error(f"--min-length {args.min_length:g}: give a length in millimetres above 0")
    try:
        args.scene = SceneParams(camera_distance=tuple(args.camera_distance), camera_tilt_deg=tuple(args.camera_tilt))
    except PsorrError as exc:
        parser.error(f"--camera-distance {args.camera_distance} / --camera-tilt {args.camera_tilt}: {exc}")
    if args.cad is not None and not args.cad.is_dir():
        parser.error(f"{args.cad}: no such folder; give a folder of meshes with --cad (the Prusa i3 parts: see "
                     f"../shared/cad/README.md)")
    return args


def _methods(chosen: list[str], library, meshes: dict) -> dict:
    """name -> recognize(cloud, rng) -> detections, each trained once for the whole half."""
    from peer_fpfh import recognize_fpfh
    from peer_o3d_global import recognize_o3d_global
    from peer_opencv import _cv2, recognize_ppf_opencv

    from psorr.recognize import Recognizer
    from psorr.recognize_params import RecognizeParams

    def ours(method: str, params: RecognizeParams | None = None):
        recognizer = Recognizer(library, method, params)
        return lambda cloud, rng: recognizer.recognize(cloud, rng).detections

    makers = {
        "psorr": lambda: ours("psorr"), "orr": lambda: ours("orr"),
        "o3d_global": lambda: lambda cloud, rng: recognize_o3d_global(meshes, cloud, rng),
        "fpfh": lambda: lambda cloud, rng: recognize_fpfh(meshes, cloud, rng),
        "opencv_ppf": lambda: (_cv2(), lambda cloud, rng: recognize_ppf_opencv(meshes, cloud, rng))[1],
    }
    methods = {}
    for name in chosen:
        try:
            methods[name] = makers[name]()
        except PsorrError as exc:
            print(f"skipping {name}: {exc}", file=sys.stderr)
    return methods


def _scene_plan(names: list[str], split: str, args) -> list[tuple[SceneKind, list | None, list[int]]]:
    """(kind, the parts to show or None to draw them, seed) of every scene of the half."""
    if args.quick:  # the first four parts alone, one clutter and one occluded scene
        return gp.scene_plan(SPLIT_SEED[split], names[:4], 1, 1, 1)
    return gp.scene_plan(SPLIT_SEED[split], names, args.singles, args.clutter, args.occluded)


def _half(split: str, meshes: dict) -> tuple[list[str], dict, dict]:
    """(part names, name -> mesh of the library's parts, name -> mesh of the distractors) of a half."""
    names = sorted(gp.folder_split(meshes)[split])
    if not names:
        raise SplitError(f"the {split} half of these {len(meshes)} parts is empty: run with --split all")
    parts = {n: meshes[n] for n in names}
    return names, parts, {**{n: m for n, m in meshes.items() if n not in parts}, **simple_shapes()}


def _scene_record(scene, seed: list[int]) -> dict:
    return {"kind": str(scene.kind), "seed": seed, "distractors": [d.name for d in scene.distractors],
            "instances": [{"part": i.name, "visibility": round(v, 3), "seen_share": round(s, 3)}
                          for i, v, s in zip(scene.instances, scene.visibility, scene.seen_share)]}


def run_split(split: str, meshes: dict, paths: dict, args) -> dict:
    """The half's results (JSON): its parts' class table, its scenes, and per method per scene the time,
    the instances found, the false detections and per instance the nearest ADD of a detection of its
    model (mm); and sketches of its first scene of each kind."""
    from psorr.library.models import ModelLibrary

    names, parts, distractors = _half(split, meshes)
    infos = {n: part_info(n, parts[n]) for n in tqdm(names, desc=f"{split}: symmetries and classes", file=sys.stderr)}
    library = ModelLibrary.from_meshes([paths[n] for n in names], units=args.units,
                                       progress=lambda p: tqdm(p, desc=f"{split}: training", file=sys.stderr))
    train_ms = _training_ms(names, paths, args.units, split) if {"psorr", "orr"} & set(args.methods.split(",")) else {}
    methods = _methods(args.methods.split(","), library, parts)
    results = {m: {"ms": [], "false": [], "left_open": [], "found": [], "add_mm": []} for m in methods}
    scenes, sketches, start = [], {}, time.perf_counter()
    plan = _scene_plan(names, split, args)
    for kind, shown, seed in tqdm(plan, desc=f"{split}: scenes, every method", file=sys.stderr):
        scene = mesh_scene(np.random.default_rng(seed), parts, kind, names=shown, distractors=distractors,
                           params=args.scene)
        scenes.append(_scene_record(scene, seed))
        for method, recognize in methods.items():
            begin = time.perf_counter()
            detections = recognize(scene.cloud, np.random.default_rng(0))
            results[method]["ms"].append(round((time.perf_counter() - begin) * 1e3, 1))
            found, correct = grade(scene, detections, infos)
            results[method]["found"].append(found)
            results[method]["false"].append(correct.count(False))
            results[method]["left_open"].append(left_open(scene, detections, found, correct, infos))
            results[method]["add_mm"].append([None if a is None else round(a * 1e3, 1)
                                              for a in nearest_add(scene, detections, infos)])
            if str(kind) not in sketches and method == next(iter(methods)):
                sketches[str(kind)] = sketch(seed, str(kind), shown, method, detections, found, correct)
    core = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else "?"
    conditions = (f"run {time.strftime('%Y-%m-%d')} in {(time.perf_counter() - start) / 60:.0f} min on core {core} "
                  f"of {os.cpu_count()}" + (f"; {args.note}" if args.note else "") + _camera_note(args.scene))
    return {"parts": [class_row(infos[n]) for n in names], "scenes": scenes, "methods": results,
            "sketches": list(sketches.values()), "conditions": conditions, "train_ms": train_ms}


def _other_camera(scene: SceneParams) -> tuple[float, float, float, float] | None:
    """(near, far, least, most) of a camera other than the benchmark's; None for its own."""
    ranges = (*scene.camera_distance, *scene.camera_tilt_deg)
    return None if ranges == (*SceneParams().camera_distance, *SceneParams().camera_tilt_deg) else ranges


def _camera_note(scene: SceneParams) -> str:
    """What the conditions say of a camera other than the benchmark's."""
    other = _other_camera(scene)
    return "" if other is None else "; the camera {:g}-{:g} m from the table, tilted {:g}-{:g} degrees".format(*other)


def _camera_stem(scene: SceneParams) -> str:
    """The results' name suffix for a camera other than the benchmark's ('' for its own)."""
    other = _other_camera(scene)
    return "" if other is None else "-camera-{:g}-{:g}m-{:g}-{:g}deg".format(*other)


def _training_ms(names: list[str], paths: dict, units: str, split: str) -> dict[str, float]:
    """name -> ms to train that one model from its mesh file as a user's first run does (the cache off)."""
    from psorr.library.models import ModelLibrary

    return {n: round(ModelLibrary.from_meshes([paths[n]], units=units, use_cache=False).train_ms, 1)
            for n in tqdm(names, desc=f"{split}: training timed, no cache", file=sys.stderr)}


def _drawn(data: dict, meshes: dict, scene_params: SceneParams) -> list:
    """The last half's sketched scenes, rendered again from their seeds."""
    import trimesh
    from generalization_parts import ADD_SAMPLES

    split = list(data["splits"])[-1]
    names, parts, distractors = _half(split, meshes)
    samples = {n: np.asarray(trimesh.sample.sample_surface(parts[n], ADD_SAMPLES, seed=0)[0]) for n in names}
    return [drawn_scene(split, entry, mesh_scene(np.random.default_rng(entry["seed"]), parts, entry["kind"],
                                                 names=entry["shown"], distractors=distractors,
                                                 params=scene_params), samples)
            for entry in data["splits"][split].get("sketches", [])]


def _merged(old: dict | None, new: dict) -> dict:
    """The new run of a half, keeping the methods it did not run from the old one when both ran the same
    scenes (the peers need not rerun when only our recognizer changed); the sketches are PSORR's. Each
    method's run conditions are kept beside it ("runs"), and the half's conditions line groups them."""
    if not old or old["scenes"] != new["scenes"]:
        return new
    kept = {m: r for m, r in old["methods"].items() if m not in new["methods"]}
    if not kept:
        return new
    methods = {**kept, **new["methods"]}
    runs = {**{m: old.get("runs", {}).get(m, old["conditions"]) for m in kept},
            **{m: new["conditions"] for m in new["methods"]}}
    order = [m for m in METHODS if m in methods]
    grouped: dict[str, list[str]] = {}
    for m in order:
        grouped.setdefault(runs[m], []).append(m)
    return {**new, "methods": {m: methods[m] for m in order}, "runs": {m: runs[m] for m in order},
            "train_ms": new.get("train_ms") or old.get("train_ms", {}),
            "sketches": new["sketches"] if "psorr" in new["methods"] else old.get("sketches", []),
            "conditions": "; ".join(f"{', '.join(ms)}: {c}" for c, ms in grouped.items())}


def main(argv=None) -> int:
    args = _arguments(argv)
    if args.cad is None and not DEFAULT_CAD.is_dir():
        print(f"no parts under {DEFAULT_CAD}: nothing to benchmark (pass --cad DIR)", file=sys.stderr)
        return 0
    args.cad = args.cad or DEFAULT_CAD
    paths = {p.stem: p for p in sorted(args.cad.iterdir()) if p.suffix.lower() in MESH_SUFFIXES}
    meshes, short = checked_split(load_meshes(args.cad, args.units), args.cad, args.min_length / 1e3)
    print(f"{len(meshes)} parts of at least {args.min_length:g} mm in {args.cad}"
          + (f"; left out as shorter: {', '.join(short)}" if short else "; none shorter"), file=sys.stderr)
    base = ("generalization" if gp.is_prusa(meshes) else f"generalization-{args.cad.resolve().name}") + _camera_stem(
        args.scene)
    stem = f"{base}.quick" if args.quick else base
    json_path = args.out / f"{stem}.json"
    data = json.loads(json_path.read_text()) if json_path.exists() else {"splits": {}}
    if args.report_only and not data["splits"]:
        sys.exit(f"{json_path} holds no results to report: run without --report-only first")
    for split in () if args.report_only else (("dev", "test") if args.split == "both" else (args.split,)):
        data["splits"][split] = _merged(data["splits"].get(split), run_split(split, meshes, paths, args))
    data["splits"] = {k: data["splits"][k] for k in HALVES if k in data["splits"]}
    text = report(data)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / f"{stem}.md").write_text(text)
    json_path.write_text(json.dumps(data, indent=1) + "\n")
    plot(data, _drawn(data, meshes, args.scene), args.out / f"{stem}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
