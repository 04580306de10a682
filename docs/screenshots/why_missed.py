"""The Rerun viewer screenshots of docs/why-missed.md: the peers benchmark's occluded clutter scene 5,
recognised with a recording, then shown in the native viewer with one blueprint per step and saved.

    python docs/screenshots/why_missed.py [--out docs/screenshots]

Needs the viz extra (``pip install 'psorr[viz]'``) and a display for the viewer; on a machine without one,
Xvfb and a software Vulkan driver do (Debian: ``apt-get install xvfb mesa-vulkan-drivers``; then
``xvfb-run -a -s "-screen 0 6000x4000x24" python docs/screenshots/why_missed.py``: a screen over twice the
viewer's window keeps the pointer, which starts in the screen's middle, off the pictures).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
SCENE = 5
WINDOW = "1200x760"
WIDTH = 1200  # px of the saved picture (the viewer renders at twice the window's size)
UP = [0.0, -1.0, 0.0]  # the cloud's frame is OpenCV's: y points down
FINE_RADIUS = 0.0003  # m: the cloud's points as drawn in the first picture


def shots(bracket: np.ndarray, centre: np.ndarray, meshes: list[str]) -> dict:
    """name -> (the entities shown, the eye's position, the point it looks at), camera frame (m): the eye on
    the way to the sensor, a little above its line of sight."""
    above = _eye(centre, 0.32)
    near = _eye(bracket, 0.16)
    return {
        "1_cloud_and_detections": (["/recognition/cloud", *meshes], above, centre),
        "2_decomposition": (["/recognition/cloud", "/recognition/decomposition/scene/boxes"], near, bracket),
        "3_candidates": (["/recognition/cloud", "/recognition/candidates/**"], above, centre),
        "4_rejected": (["/recognition/cloud", "/recognition/rejected"], above, centre),
    }


def _eye(target: np.ndarray, distance: float) -> np.ndarray:
    towards = -target / np.linalg.norm(target) + np.array([0.0, -0.3, 0.0])
    return target + distance * towards / np.linalg.norm(towards)


def record(rrd: Path) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Recognise the scene into ``rrd``; (the bracket's position, the scene's middle), camera frame (m), and
    the entity paths of the detections' meshes."""
    sys.path.insert(0, str(REPO / "benchmarks"))
    from peer_common import catalog_library, clutter_scene

    from psorr.recognize import Recognizer
    from psorr.viz import RerunLogger

    catalog, meshes, library, *_ = catalog_library()
    scene = clutter_scene(SCENE, catalog, meshes)
    with RerunLogger(rrd) as logger:
        Recognizer(library).recognize(scene.cloud, np.random.default_rng(0), observer=logger)
    bracket = next(i for i in scene.instances if i.name == "bracket").T_camera_model[:3, 3]
    middle = np.mean([i.T_camera_model[:3, 3] for i in scene.instances], axis=0)
    from rerun.chunk import RrdReader

    paths = {chunk.entity_path for chunk in RrdReader(rrd).stream()}
    return bracket, middle, sorted(p for p in paths if p.startswith("/recognition/detections/") and p.endswith("/mesh"))


def screenshot(rrd: Path, name: str, contents: list[str], eye, target, out: Path, scratch: Path) -> Path:
    """One viewer screenshot of ``contents`` seen from ``eye``, saved as ``out/why_missed_<name>.jpg``."""
    import rerun as rr
    import rerun.blueprint as rrb
    from PIL import Image

    # Every step of the recording at once, wherever the time cursor is: each rejection is logged at a step
    # of its own, and a view shows only the latest before the cursor otherwise.
    everything = rrb.VisibleTimeRange("stage", start=rrb.TimeRangeBoundary.infinite(),
                                      end=rrb.TimeRangeBoundary.infinite())
    # The cloud's points drawn finer than recorded, so that the posed meshes, which lie on its surface, show.
    fine = {"/recognition/cloud": rr.Points3D.from_fields(radii=FINE_RADIUS).visualizer()}
    view = rrb.Spatial3DView(origin="/", contents=contents, name=name.split("_", 1)[1].replace("_", " "),
                             eye_controls=rrb.EyeControls3D(position=eye, look_target=target, eye_up=UP),
                             time_ranges=everything, overrides=fine if name.startswith("1_") else None)
    blueprint = scratch / f"{name}.rbl"
    # The time cursor at the recording's end, where the meshes (shown as of the cursor) are all logged.
    end = rrb.TimePanel(timeline="stage", play_state="following", state="collapsed")
    rrb.Blueprint(view, end, collapse_panels=True).save("psorr", str(blueprint))
    raw = scratch / f"{name}.png"
    subprocess.run([sys.executable, "-m", "rerun", str(rrd), str(blueprint), "--screenshot-to", str(raw),
                    "--window-size", WINDOW], check=True, capture_output=True)
    image = Image.open(raw).convert("RGB")
    image = image.resize((WIDTH, round(image.height * WIDTH / image.width)), Image.LANCZOS)
    path = out / f"why_missed_{name}.jpg"  # a cloud's dots are noise to PNG: JPEG is a seventh the size
    image.save(path, quality=85, optimize=True)
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "screenshots")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp)
        rrd = scratch / f"clutter{SCENE}.rrd"
        bracket, middle, meshes = record(rrd)
        for name, (contents, eye, target) in shots(bracket, middle, meshes).items():
            print(screenshot(rrd, name, contents, eye.tolist(), target.tolist(), args.out, scratch))
    return 0


if __name__ == "__main__":
    sys.exit(main())
