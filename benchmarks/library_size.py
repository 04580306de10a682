"""Recall and time against the size of the library: the same scenes, recognised by PSORR with ever larger libraries.

A user trains every part they have. The scenes here hold the first ten parts (by name) of the dev half of the
Prusa i3 parts at least 25 mm long (generalization_parts.py's split): each alone in its stable rests, in clutter
of 3-5 with 1-3 distractors, and the same with an arm across the view, as benchmarks/generalization.py builds
them. The distractors are simple shapes only (a box, a cylinder, a ball, a cone), in no library, so a model a
larger library adds can be found only falsely. Each scene is recognised with three libraries: the ten parts;
the whole dev half; every part of both halves. Graded as generalization.py grades (a symmetry-aware ADD under
0.1 of the diameter; clutter and occlusion count the instances at least 30% visible). One core.

    python benchmarks/library_size.py [--singles 2] [--clutter 10] [--occluded 10] [--out benchmarks/results]
    python benchmarks/library_size.py --cad MY_PARTS --units m    # your own folder: its dev half's first ten

Writes library_size.{md,json,png} (library_size-FOLDER.* for another folder).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import generalization_parts as gp
import numpy as np
from generalization import DEFAULT_CAD, SPLIT_SEED
from library_size_report import false_table, plot, table
from tqdm import tqdm

from psorr.io.meshes import MESH_SUFFIXES, UNITS
from psorr.synthetic.mesh_scenes import SceneKind, load_meshes, mesh_scene, simple_shapes

SHOWN = 10  # parts in the scenes, and in the smallest library: the size the benchmark asks for
SEED = SPLIT_SEED["dev"] + 100  # scenes of their own: not the generalization benchmark's


def _arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--singles", type=int, default=2, help="lone scenes a part")
    parser.add_argument("--clutter", type=int, default=10)
    parser.add_argument("--occluded", type=int, default=10)
    parser.add_argument("--cad", type=Path, default=None, help="a folder of meshes (default: the Prusa i3 parts)")
    parser.add_argument("--units", choices=UNITS, default="mm")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "results")
    return parser.parse_args(argv)


def libraries(meshes: dict, folder: Path | str = "the folder") -> tuple[list[str], list[list[str]]]:
    """(the parts the scenes show, the libraries' part names, smallest first)."""
    halves = gp.folder_split(meshes)
    dev = sorted(halves["dev"])
    if len(dev) <= SHOWN:
        raise gp.SplitError(f"{folder}: the dev half holds {len(dev)} of its {len(meshes)} parts; this benchmark "
                            f"shows {SHOWN} and adds more, so it needs at least {2 * SHOWN + 1} parts of at least "
                            f"{gp.MIN_LENGTH * 1e3:g} mm (benchmarks/generalization.py --split all takes fewer)")
    shown = dev[:SHOWN]
    return shown, [shown, dev, sorted(meshes)]


def run(meshes: dict, paths: dict, args) -> dict:
    """The results (JSON): per library its size and per scene the instances found, false detections and ms, for
    the meshes of folder ``args.cad`` in ``args.units``."""
    from psorr.library.models import ModelLibrary
    from psorr.recognize import Recognizer

    shown, named = libraries(meshes, args.cad)
    parts = {n: meshes[n] for n in shown}
    infos = {n: gp.part_info(n, parts[n]) for n in shown}
    recognizers = [Recognizer(ModelLibrary.from_meshes([paths[n] for n in names], units=args.units), "psorr")
                   for names in tqdm(named, desc="training", file=sys.stderr)]
    rows = [{"models": len(names), "found": [], "counted": [], "false": [], "false_models": [], "ms": []}
            for names in named]
    kinds, start = [], time.perf_counter()
    plan = gp.scene_plan(SEED, shown, args.singles, args.clutter, args.occluded)
    for kind, names, seed in tqdm(plan, desc="scenes, every library", file=sys.stderr):
        scene = mesh_scene(np.random.default_rng(seed), parts, kind, names=names, distractors=simple_shapes())
        kinds.append(str(kind))
        counted = [kind == SceneKind.SINGLE or v >= 0.3 for v in scene.visibility]
        for row, recognizer in zip(rows, recognizers):
            begin = time.perf_counter()
            detections = recognizer.recognize(scene.cloud, np.random.default_rng(0)).detections
            row["ms"].append(round((time.perf_counter() - begin) * 1e3, 1))
            found, correct = gp.grade(scene, detections, infos)
            row["found"].append(sum(f and c for f, c in zip(found, counted)))
            row["counted"].append(sum(counted))
            row["false"].append(correct.count(False))
            row["false_models"].append([d.model for d, ok in zip(detections, correct) if not ok])
    return {"shown": shown, "libraries": named, "kinds": kinds, "rows": rows,
            "conditions": f"run {time.strftime('%Y-%m-%d')} in {(time.perf_counter() - start) / 60:.0f} min, one core"}


def main(argv=None) -> int:
    args = _arguments(argv)
    if args.cad is None and not DEFAULT_CAD.is_dir():
        print(f"no parts under {DEFAULT_CAD}: nothing to benchmark (pass --cad DIR)", file=sys.stderr)
        return 0
    cad = args.cad = args.cad or DEFAULT_CAD
    paths = {p.stem: p for p in sorted(cad.iterdir()) if p.suffix.lower() in MESH_SUFFIXES}
    meshes, _ = gp.checked_split(load_meshes(cad, args.units), cad)
    stem = "library_size" if gp.is_prusa(meshes) else f"library_size-{cad.resolve().name}"
    data = run(meshes, paths, args)
    text = (f"{table(data)}\n\nFalse detections by model:\n\n{false_table(data)}\n\n"
            f"Scenes of {', '.join(data['shown'])}; {data['conditions']}.\n")
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / f"{stem}.md").write_text(text)
    (args.out / f"{stem}.json").write_text(json.dumps(data, indent=1) + "\n")
    plot(data, args.out / f"{stem}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
