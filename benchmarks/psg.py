"""PSG matching against PSORR on models of few and many primitives, on one core.

Each model stands alone on the table in seeded scenes (the catalog's renderer: 0.65-0.8 m above the
table, 20-30 degrees from the vertical, Kinect noise), and both methods look for it among a library of
the 8 catalog parts and two generated assemblies of many planes:

- a machined housing: a 120 x 90 x 60 mm block with a stepped pocket, two side slots and chamfered
  corners;
- a bracket assembly: a base plate with an upright, two gussets and a top flange.

Method AUTO runs beside them: PSG's cliques for the models of at least ``PsgParams.auto_primitives``
primitives, PSORR's pairs for every model.

Graded by symmetry-aware ADD under 0.1 of the diameter. The table gives each model's primitive count
(planes, cylinders), each method's recall and time, and the crossover: the fewest primitives at which
PSG is the faster of PSORR and PSG.

Each model gets 8 scenes, and each scene is recognised twice by each method and the faster run timed
(`timing.best_of`): most lone scenes are settled before a method's own search runs, and with 4 scenes a
model the largest models had one or two searched scenes each, so that one run's 10% wander decided which
method was faster (the crossover moved from 17 to 31 primitives between runs).

    python benchmarks/psg.py [--seeds 8] [--repeats 2] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from functools import partial
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import numpy as np
import trimesh
from psg_report import METHODS, report
from timing import best_of
from tqdm import tqdm

from psorr.decomposition.detail import DetailParams
from psorr.hypotheses.outline import OutlineParams
from psorr.hypotheses.psg import PsgParams
from psorr.hypotheses.single_cylinder import SingleCylinderParams
from psorr.hypotheses.single_plane import SinglePlaneParams
from psorr.library.models import ModelLibrary
from psorr.recognize import Recognizer
from psorr.recognize_params import RecognizeParams
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.mesh_symmetry import find_symmetries, match_detections
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import PrimitiveKind

ROOT = Path(__file__).resolve().parents[1]
# PSG with the stages it shares with PSORR off (the pairs after the cliques, single faces and cylinders,
# outlines, the second look): what the cliques find on their own.
CLIQUES_ALONE = RecognizeParams(psg=PsgParams(pairs_after=False), single_plane=SinglePlaneParams(enabled=False),
                                single_cylinder=SingleCylinderParams(enabled=False),
                                outline=OutlineParams(enabled=False), detail=DetailParams(fine_voxel=None))


def _box(extents, centre) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents)
    box.apply_translation(centre)
    return box


def housing() -> trimesh.Trimesh:
    """A block with a stepped pocket in its top, a slot in two sides and its vertical edges chamfered."""
    block = _box((0.12, 0.09, 0.06), (0, 0, 0.03))
    cuts = [_box((0.07, 0.05, 0.03), (0, 0, 0.06)), _box((0.04, 0.03, 0.05), (0.01, 0, 0.06)),
            _box((0.14, 0.02, 0.015), (0, 0, 0.02)), _box((0.02, 0.11, 0.015), (0.035, 0, 0.035))]
    for sx in (-1, 1):
        for sy in (-1, 1):
            corner = _box((0.02, 0.02, 0.08), (sx * 0.06, sy * 0.045, 0.03))
            corner.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 4, (0, 0, 1),
                                                                           (sx * 0.06, sy * 0.045, 0)))
            cuts.append(corner)
    return trimesh.boolean.difference([block, *cuts], engine="manifold")


def bracket_assembly() -> trimesh.Trimesh:
    """A base plate, an upright at its back, two triangular-ish gussets (stepped blocks) and a top flange."""
    parts = [_box((0.12, 0.08, 0.008), (0, 0, 0.004)), _box((0.12, 0.008, 0.07), (0, 0.036, 0.035)),
             _box((0.008, 0.03, 0.03), (-0.04, 0.017, 0.023)), _box((0.008, 0.03, 0.03), (0.04, 0.017, 0.023)),
             _box((0.008, 0.015, 0.05), (-0.04, 0.025, 0.033)), _box((0.008, 0.015, 0.05), (0.04, 0.025, 0.033)),
             _box((0.12, 0.03, 0.008), (0, 0.025, 0.074))]
    return trimesh.boolean.union(parts, engine="manifold")


def library_and_meshes(folder: Path):
    catalog = load_catalog()
    meshes = {name: catalog[name].load_mesh() for name in sorted(catalog)}
    meshes["housing"], meshes["bracket_assembly"] = housing(), bracket_assembly()
    paths = []
    for name, mesh in meshes.items():
        path = catalog[name].mesh_path if name in catalog else folder / f"{name}.stl"
        if name not in catalog:
            mesh.export(path)
        paths.append(path)
    return ModelLibrary.from_meshes(paths), meshes


def _recognition(recognizer: Recognizer, cloud):
    return recognizer.recognize(cloud, np.random.default_rng(0))


def run(seeds: int, repeats: int) -> list[dict]:
    with tempfile.TemporaryDirectory() as folder:
        library, meshes = library_and_meshes(Path(folder))
    recognizers = {"psorr": Recognizer(library, "psorr"), "psg": Recognizer(library, "psg"),
                   "auto": Recognizer(library, "auto"), "cliques": Recognizer(library, "psg", CLIQUES_ALONE)}
    known = {m.name: (m.points[::10], find_symmetries(meshes[m.name]), m.diameter) for m in library.models}
    # The models whose cliques AUTO matches, as its recognizer chose them.
    auto_cliques = {m.name for m in recognizers["auto"].psg.models} if recognizers["auto"].psg else set()
    rows = []
    with tqdm(total=len(meshes) * seeds, desc="scenes", file=sys.stderr) as bar:
        for name in meshes:
            graph = library.model(name).graph
            row = {"model": name, "planes": graph.count(PrimitiveKind.PLANE),
                   "cylinders": graph.count(PrimitiveKind.CYLINDER),
                   "auto_cliques": name in auto_cliques}
            for method in METHODS:
                row[method] = {"found": 0, "false": 0, "ms": [], "searched": []}
            for seed in range(seeds):
                scene = workpiece_scene(np.random.default_rng(500 + seed), meshes, [name])
                for method, recognizer in recognizers.items():
                    recognition, ms = best_of(repeats if method != "cliques" else 1, partial(
                        _recognition, recognizer, scene.cloud))
                    row[method]["ms"].append(ms)
                    # Decomposed: the method's own search ran; else the resting-pose trial, which both share,
                    # settled the scene (docs/decisions/0066-resting-poses-first.md).
                    row[method]["searched"].append(recognition.stats.decomposition_ms > 0)
                    found, correct = match_detections(scene.instances, recognition.detections, known.get)
                    row[method]["found"] += sum(found)
                    row[method]["false"] += correct.count(False)
                bar.update()
            row["seeds"] = seeds
            rows.append(row)
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=8, help="scenes per model")
    parser.add_argument("--repeats", type=int, default=2,
                        help="runs of each scene per method, the fastest timed (the cliques alone: one)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    report(run(args.seeds, args.repeats), args.out, PsgParams().auto_primitives)
    return 0


if __name__ == "__main__":
    sys.exit(main())
