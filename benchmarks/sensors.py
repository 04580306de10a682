"""PSORR on clouds from other sensors than the Kinect, and on clouds stripped of their image layout.

The same seeded 4-part clutter scenes (an arm-sized capsule across the view, all 8 catalog parts as
candidates) are rendered by a Kinect v1 (640x480, 525 px) and by a 1280x720 sensor at 910 px (a
RealSense D435's colour-aligned depth, roughly), each as an organised image and as the same points
with the NaN pixels stripped (an unorganised cloud, as PCL pipelines pass on). Graded as in
peers.py: a detection is correct under a symmetry-aware ADD of 0.1 x the model diameter.

Over 12 scenes the two sensors' recall differed by two parts, which 36 showed to be noise: the
default is 36 (about 5 minutes).

    python benchmarks/sensors.py [--clutter 36]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import numpy as np
from peer_common import catalog_library, clutter_scene, grade
from tqdm import tqdm

from psorr.recognize import Recognizer
from psorr.sensing.camera import CameraIntrinsics
from psorr.types import PointCloud

ROOT = Path(__file__).resolve().parents[1]
SENSORS = {"Kinect v1 640x480": CameraIntrinsics(),
           "1280x720 at 910 px": CameraIntrinsics(width=1280, height=720, fx=910.0, fy=910.0, cx=639.5, cy=359.5)}
LAYOUTS = ("organised image", "NaNs stripped")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--clutter", type=int, default=36, help="clutter scenes per sensor (seeds 0..N-1)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    catalog, meshes, library, samples, diameters = catalog_library()
    psorr = Recognizer(library, "psorr")
    rows = {(s, layout): {"found": 0, "instances": 0, "false": 0, "ms": []} for s in SENSORS for layout in LAYOUTS}
    with tqdm(total=len(rows) * args.clutter, desc="scenes", file=sys.stderr) as bar:
        for sensor, intrinsics in SENSORS.items():
            for seed in range(args.clutter):
                scene = clutter_scene(seed, catalog, meshes, intrinsics)
                clouds = (scene.cloud, PointCloud(scene.cloud.points[scene.cloud.valid_mask]))
                for layout, cloud in zip(LAYOUTS, clouds):
                    start = time.perf_counter()
                    detections = psorr.recognize(cloud, np.random.default_rng(0)).detections
                    row = rows[sensor, layout]
                    row["ms"].append((time.perf_counter() - start) * 1e3)
                    found, false = grade(scene, detections, catalog, samples, diameters)
                    row["found"] += found
                    row["instances"] += len(scene.instances)
                    row["false"] += false
                    bar.update()
    lines = [f"PSORR on {args.clutter} seeded 4-part clutter scenes per sensor (capsule occluder, 8 candidate "
             "parts), 1 core", "",
             "| sensor | cloud | recall | false detections | median ms / scene |", "|---|---|---|---|---|"]
    for (sensor, layout), r in rows.items():
        lines.append(f"| {sensor} | {layout} | {r['found']}/{r['instances']} = {r['found'] / r['instances']:.2f} | "
                     f"{r['false']} | {np.median(r['ms']):.0f} |")
    text = "\n".join(lines)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "sensors.md").write_text(text + "\n")
    table = [{"sensor": s, "cloud": layout, **r} for (s, layout), r in rows.items()]
    (args.out / "sensors.json").write_text(json.dumps({"clutter_scenes": args.clutter, "rows": table}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
