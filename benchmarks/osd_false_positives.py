"""False detections on real Kinect clouds that hold none of our parts, PSORR and ORR, on one core;
each also with the continuation check off (AcceptParams.max_continued=None, psorr.acceptance.continuation),
to show what the check removes.

The OSD learn set's 45 clouds show boxes, stacked boxes, occluded objects and cylinders on a table.
None is a catalog part, so every detection of the 8 catalog parts there is false. Prints, per method,
the detections per scene group and per model and the scenes with any, and writes the list (with poses)
and a picture of what each method reports with its default settings.

    python benchmarks/osd_false_positives.py [--osd DIR] [--methods psorr,orr] [--no-check-off] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path

import _single_core  # noqa: F401  (must precede numpy)
import numpy as np
from tqdm import tqdm

from psorr import AcceptParams, RecognizeParams
from psorr.io.clouds import read_cloud
from psorr.library.models import ModelLibrary
from psorr.recognize import Recognizer
from psorr.synthetic.catalog import load_catalog

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OSD = ROOT.parent / "shared" / "osd" / "learn"
# Scene groups of the OSD learn set, by index (its README).
GROUPS = (("boxes", range(0, 17)), ("stacked boxes", range(17, 25)), ("occluded", range(25, 33)),
          ("cylinders", range(33, 45)))


def _group(index: int) -> str:
    return next((name for name, indices in GROUPS if index in indices), "other")


def _picture(path: Path, shown, library, columns: int = 4) -> None:
    """Each (title, cloud, detections) of ``shown`` in a panel, cropped to its detections."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from psorr.viz.render import draw_detections

    rows = -(-len(shown) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(3.2 * columns, 3.2 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, (title, cloud, detections) in zip(axes.ravel(), shown):
        width, height, drawn = draw_detections(ax, cloud, detections, library, point_size=2.0)
        pixels = np.vstack(drawn)
        (u0, v0), (u1, v1) = pixels.min(axis=0) - 60, pixels.max(axis=0) + 60
        side = max(u1 - u0, v1 - v0)  # square panels, so every crop shows at one scale per panel
        uc, vc = (u0 + u1) / 2, (v0 + v1) / 2
        ax.set_xlim(max(uc - side / 2, 0), min(uc + side / 2, width))
        ax.set_ylim(min(vc + side / 2, height), max(vc - side / 2, 0))
        ax.set_title(title, fontsize=8)
    fig.suptitle("False detections on the OSD learn clouds (default settings); every one is false", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--osd", type=Path, default=DEFAULT_OSD, help="folder of learn*.pcd")
    parser.add_argument("--methods", default="psorr,orr")
    parser.add_argument("--no-check-off", dest="check_off", action="store_false",
                        help="run only the default settings, not also with the continuation check off")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args(argv)
    paths = sorted(args.osd.glob("learn*.pcd"), key=lambda p: int(p.stem[5:]))
    if not paths:
        print(f"no OSD clouds under {args.osd}: nothing to benchmark (pass --osd DIR)", file=sys.stderr)
        return 0
    catalog = load_catalog()
    library = ModelLibrary.from_meshes([catalog[n].mesh_path for n in sorted(catalog)])
    records, shown = {}, []
    settings = [(m, RecognizeParams()) for m in args.methods.split(",")]
    if args.check_off:
        settings += [(m, RecognizeParams(acceptance=AcceptParams(max_continued=None))) for m in args.methods.split(",")]
    for method, params in settings:
        label = method if params.acceptance.max_continued is not None else f"{method}, continuation check off"
        recognizer = Recognizer(library, method, params)
        records[label] = []
        for path in tqdm(paths, desc=label, file=sys.stderr):
            cloud = read_cloud(path)
            result = recognizer.recognize(cloud, np.random.default_rng(0))
            records[label].append({"scene": path.stem, "group": _group(int(path.stem[5:])),
                                    "detections": [{"model": d.model, "score": round(d.score, 3),
                                                    "pose": np.round(d.T_cloud_model, 5).tolist()}
                                                   for d in result.detections]})
            if result.detections and params.acceptance.max_continued is not None:
                shown.append((f"{label}: {path.stem}", cloud, result.detections))
    lines = [f"{len(paths)} OSD learn clouds (none holds a catalog part), all 8 catalog parts as candidates; "
             "every detection is false.", "",
             "| method | false detections | clouds with any | per cloud | median score | score >= 0.8 | "
             + " | ".join(name for name, _ in GROUPS) + " |",
             "|---|---:|---:|---:|---:|---:|" + "---:|" * len(GROUPS)]
    for method, rows in records.items():
        scores = [d["score"] for r in rows for d in r["detections"]]
        by_group = Counter(r["group"] for r in rows for _ in r["detections"])
        lines.append(f"| {method} | {len(scores)} | {sum(bool(r['detections']) for r in rows)} | "
                     f"{len(scores) / len(rows):.2f} | {np.median(scores) if scores else 0:.2f} | "
                     f"{sum(s >= 0.8 for s in scores)} | " + " | ".join(str(by_group[n]) for n, _ in GROUPS) + " |")
    lines.append("")
    for method, rows in records.items():
        per_model = Counter(d["model"] for r in rows for d in r["detections"])
        lines.append(f"{method} by model: " + ", ".join(f"{m} {c}" for m, c in per_model.most_common()))
    text = "\n".join(lines)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "osd_false_positives.md").write_text(text + "\n")
    (args.out / "osd_false_positives.json").write_text(json.dumps(records, indent=1) + "\n")
    if shown:
        _picture(args.out / "osd_false_positives.png", shown, library)
    return 0


if __name__ == "__main__":
    sys.exit(main())
