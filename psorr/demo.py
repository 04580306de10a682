"""`make demo`: decompose a seeded Kinect-like scene of our workpieces (and a
real Kinect cloud when run from a checkout with the OSD set beside it),
recognise the parts with a library trained from their CAD meshes, print
results tables against the ground truth and write pictures to out/demo/ under
the current directory. `make demo` then runs the robot cell's scripted
episodes (psorr-sim run tasks/demo.yaml), with this recognizer in the loop.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from psorr.decomposition import DecomposeParams, decompose
from psorr.io.clouds import read_cloud, write_cloud
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.metrics import osd_object_ids, segmentation_scores
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import PrimitiveKind
from psorr.viz.render import save_decomposition_png

OUT = Path("out") / "demo"  # under the current directory: an installed psorr has no repository to write in
OSD_SCENE = Path("shared") / "osd" / "learn" / "learn35.pcd"  # beside a checkout, not in the package
SEED = 0
PARTS = ["chassis", "transformer", "circuit_board", "flanged_hub", "u_channel"]
# Our parts are 5-14 cm across at ~0.75 m; an 8 mm voxel resolves their
# bosses and coils, where the 12 mm default is tuned for OSD-sized objects.
WORKPIECE_PARAMS = DecomposeParams(voxel_size=0.008)


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _per_object_rows(cloud, labels, graph, names):
    rows = []
    for k, name in enumerate(names, start=1):
        mine = labels[cloud.labels == k]
        prims = [p for p in np.unique(mine) if p >= 0 and (mine == p).sum() > 0.5 * (labels == p).sum()]
        kinds = [graph.primitives[p].kind for p in prims]
        covered = np.isin(mine, prims).mean() if len(mine) else 0.0
        rows.append((name, len(mine), kinds.count(PrimitiveKind.PLANE), kinds.count(PrimitiveKind.CYLINDER), covered))
    return rows


def _recognise(cloud, scene, catalog) -> None:
    """Recognise the scene's parts with all 8 catalog models and score each detection."""
    from tqdm import tqdm

    from psorr.library.models import ModelLibrary
    from psorr.recognize import Recognizer
    from psorr.synthetic.catalog import symmetric_add
    from psorr.viz.render import save_detections_png

    paths = [catalog[name].mesh_path for name in sorted(catalog)]
    library = ModelLibrary.from_meshes(
        paths, progress=lambda xs: tqdm(xs, desc="training (cached after the first run)", file=sys.stderr))
    result = Recognizer(library).recognize(cloud, np.random.default_rng(SEED))
    stats = result.stats
    print(f"\nRecognition with {len(library)} CAD-trained models (PSORR): {len(result.detections)} detections, "
          f"{stats.hypotheses} hypotheses, {stats.verify_ms_per_hypothesis:.1f} ms box verification each, "
          f"{stats.total_ms:.0f} ms in all\n")
    print(f"{'detection':<15} {'score':>5} {'seen':>5} {'ADD mm':>7} {'ADD/d':>6} {'twins open':>10}  verdict")
    found = set()
    for det in result.detections:
        model = library.model(det.model)
        errors = [(symmetric_add(model.points[::10], det.T_cloud_model, inst.T_camera_model, catalog[inst.name]), k)
                  for k, inst in enumerate(scene.instances) if inst.name == det.model]
        add, k = min(errors) if errors else (float("inf"), None)
        ok = add < 0.1 * model.diameter
        if ok:
            found.add(k)
        print(f"{det.model:<15} {det.score:>5.2f} {det.visible_fraction:>5.2f} {add * 1e3:>7.1f} "
              f"{add / model.diameter:>6.3f} {len(det.alternatives):>10}  {'correct' if ok else 'WRONG'}")
    missed = [inst.name for k, inst in enumerate(scene.instances) if k not in found]
    print(f"found {len(found)} of {len(scene.instances)} parts; missed: {', '.join(missed) or 'none'}")
    overlay = save_detections_png(OUT / "workpieces_recognition.png", cloud, result.detections, library)
    print(f"picture: {overlay}")


def _checkout() -> Path | None:
    """The repository psorr runs from, or None for an installed psorr (no pyproject.toml beside the package)."""
    root = Path(__file__).resolve().parents[1]
    return root if (root / "pyproject.toml").is_file() else None


def _real_cloud() -> None:
    """Decompose OSD's learn35 when the OSD set is beside the checkout; say why not otherwise."""
    checkout = _checkout()
    if checkout is None:
        _log("(an installed psorr has no checkout to find the OSD set beside; skipping the real-cloud part)")
        return
    path = checkout.parent / OSD_SCENE
    if not path.is_file():
        _log(f"(no {path}; skipping the real-cloud part)")
        return
    real = read_cloud(path)
    start = time.perf_counter()
    real_result = decompose(real)
    real_ms = (time.perf_counter() - start) * 1e3
    real_scores = segmentation_scores(osd_object_ids(real.labels), real_result.labels, background=(0, 1))
    real_picture = save_decomposition_png(OUT / "osd_learn35_decomposition.png", real, real_result.labels,
                                          real_result.graph, title=f"OSD learn35 (real Kinect): "
                                          f"{len(real_result.primitives)} primitives, {real_ms:.0f} ms")
    print(f"real Kinect cloud {path.name}: {len(real_result.primitives)} primitives in {real_ms:.0f} ms, "
          f"object coverage {real_scores.coverage:.2f}, purity {real_scores.purity:.3f}; picture: {real_picture}")


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    catalog = load_catalog()
    meshes = {name: catalog[name].load_mesh() for name in PARTS}
    _log(f"rendering a seeded Kinect scene of {len(PARTS)} workpieces (seed {SEED}) ...")
    scene = workpiece_scene(np.random.default_rng(SEED), meshes, PARTS)
    cloud_path = OUT / "workpieces_scene.pcd"
    write_cloud(cloud_path, scene.cloud, compressed=True)
    cloud = read_cloud(cloud_path)  # the same path a user's file takes
    start = time.perf_counter()
    result = decompose(cloud, WORKPIECE_PARAMS, rng=np.random.default_rng(SEED))
    elapsed = (time.perf_counter() - start) * 1e3
    picture = save_decomposition_png(OUT / "workpieces_decomposition.png", cloud, result.labels, result.graph,
                                     title=f"seeded Kinect scene of {len(PARTS)} workpieces: "
                                           f"{len(result.primitives)} primitives, {elapsed:.0f} ms")
    print(f"\nDecomposition of {cloud_path} ({int(cloud.valid_mask.sum())} points, "
          f"{elapsed:.0f} ms, {len(result.primitives)} primitives, {len(result.graph.edges)} PSG edges, "
          f"voxel {WORKPIECE_PARAMS.voxel_size * 1000:.0f} mm)\n")
    print(f"{'workpiece':<15} {'points':>7} {'planes':>6} {'cylinders':>9} {'coverage':>8}")
    for name, n, planes, cylinders, covered in _per_object_rows(cloud, result.labels, result.graph, PARTS):
        print(f"{name:<15} {n:>7} {planes:>6} {cylinders:>9} {covered:>8.2f}")
    scores = segmentation_scores(cloud.labels, result.labels, background=(0,))
    print(f"{'all objects':<15} {'':>7} {'':>6} {'':>9} {scores.coverage:>8.2f}   purity {scores.purity:.3f}")
    print(f"\npicture: {picture}")
    _recognise(cloud, scene, catalog)
    _real_cloud()
    return 0


if __name__ == "__main__":
    sys.exit(main())
