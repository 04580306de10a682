"""The generalization benchmark's picture: recall by class and method on each half, the time per scene,
and a few scenes with PSORR's detections drawn over the depth image."""

from __future__ import annotations

import statistics
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from generalization_report import CLASSES, instances, recall


@dataclass(frozen=True, eq=False)
class DrawnScene:
    """One scene to draw: depth (H, W) metres, the truth and one method's detections with their grades."""

    title: str
    depth: np.ndarray
    truths: list  # (samples (N, 3) model frame, T_camera_model (4, 4), found)
    detections: list  # (samples (N, 3) model frame, T_cloud_model (4, 4), correct)
    intrinsics: object


def sketch(seed: list[int], kind: str, shown, method: str, detections, found: list[bool], correct: list[bool]) -> dict:
    """What the picture needs to draw a scene again (JSON): its seed and parts, one method's detections."""
    return {"seed": seed, "kind": kind, "shown": shown, "method": method, "found": found,
            "detections": [{"model": d.model, "T": np.round(d.T_cloud_model, 6).tolist(), "correct": c}
                           for d, c in zip(detections, correct)]}


def drawn_scene(split: str, entry: dict, scene, samples: dict) -> DrawnScene:
    """The sketch ``entry`` over its scene rendered again (the same seed gives the same scene); samples:
    model name -> (N, 3) surface samples."""
    depth = np.nan_to_num(scene.cloud.points[:, 2].reshape(scene.intrinsics.height, scene.intrinsics.width))
    dets, found = entry["detections"], entry["found"]
    title = (f"{split} {entry['kind']}: {', '.join(i.name for i in scene.instances)}"[:90]
             + f"\n{entry['method']}: {sum(found)}/{len(found)} found, {sum(not d['correct'] for d in dets)} false")
    return DrawnScene(title, depth, [(samples[i.name], i.T_camera_model, f) for i, f in zip(scene.instances, found)],
                      [(samples[d["model"]], np.array(d["T"]), d["correct"]) for d in dets if d["model"] in samples],
                      scene.intrinsics)


def _project(samples: np.ndarray, T: np.ndarray, intrinsics) -> np.ndarray:
    posed = samples @ T[:3, :3].T + T[:3, 3]
    return np.column_stack((intrinsics.fx * posed[:, 0] / posed[:, 2] + intrinsics.cx,
                            intrinsics.fy * posed[:, 1] / posed[:, 2] + intrinsics.cy))


def _recall_bars(ax, split: dict, name: str) -> None:
    present = [c for c in CLASSES if any(p["class"] == c for p in split["parts"])]
    groups = ["single", "clutter", "occluded", *present]
    methods = list(split["methods"])
    width = 0.8 / len(methods)
    for k, method in enumerate(methods):
        items = instances(split, method)
        values = []
        for g in groups:
            found, count = recall(items, kind=g) if g in ("single", "clutter", "occluded") else recall(
                items, **{"class": g})
            values.append(found / count if count else 0.0)
        ax.bar(np.arange(len(groups)) + (k - (len(methods) - 1) / 2) * width, values, width, label=method)
    ax.set_xticks(np.arange(len(groups)), groups, fontsize=8)
    ax.set_ylim(0, 1)
    ax.set_title(f"{name} half: recall (ADD < 0.1 d; clutter, occluded and classes: >= 30% seen)", fontsize=9)
    ax.legend(fontsize=7, ncol=len(methods))


def _times(ax, data: dict) -> None:
    splits = list(data["splits"])
    methods = list(dict.fromkeys(m for s in data["splits"].values() for m in s["methods"]))
    width = 0.8 / len(splits)
    for k, name in enumerate(splits):
        ms = [statistics.median(data["splits"][name]["methods"][m]["ms"]) if m in data["splits"][name]["methods"]
              else 0.0 for m in methods]
        ax.bar(np.arange(len(methods)) + (k - (len(splits) - 1) / 2) * width, ms, width, label=name)
    ax.axhline(300, color="k", ls="--", lw=0.8)
    ax.set_xticks(np.arange(len(methods)), methods, fontsize=8)
    ax.set_yscale("log")
    ax.set_title("median ms per 640x480 scene, one core (dashed: 300 ms)", fontsize=9)
    ax.legend(fontsize=7)


def _shaded(depth: np.ndarray, focal: float) -> np.ndarray:
    """(H, W) grey levels in [0, 1] lit from the top left by the depth's slopes (smoothed over the sensor's
    noise, 2 pixels), NaN without a return."""
    from scipy.ndimage import gaussian_filter

    z = np.where(depth > 0, depth, np.nan)
    dv, du = np.gradient(gaussian_filter(np.nan_to_num(z, nan=float(np.nanmedian(z))), 2.0))
    return np.clip(0.55 + 0.3 * (du - dv) * focal / z, 0.0, 1.0)


def _scene(ax, scene: DrawnScene) -> None:
    """The depth image, shaded by its slopes, cropped to the parts with a margin of 40 pixels."""
    corners = np.vstack([_project(samples, T, scene.intrinsics) for samples, T, _ in scene.truths])
    (u0, v0), (u1, v1) = corners.min(axis=0) - 40, corners.max(axis=0) + 40
    u0, v0 = max(u0, 0), max(v0, 0)
    u1, v1 = min(u1, scene.intrinsics.width - 1), min(v1, scene.intrinsics.height - 1)
    ax.imshow(_shaded(scene.depth, scene.intrinsics.fx), cmap="gray", vmin=0, vmax=1)
    ax.set_xlim(u0, u1)
    ax.set_ylim(v1, v0)
    for samples, T, found in scene.truths:
        uv = _project(samples, T, scene.intrinsics)
        ax.scatter(uv[:, 0], uv[:, 1], s=0.3, c="tab:blue" if found else "gold", alpha=0.5)
    for samples, T, correct in scene.detections:
        uv = _project(samples, T, scene.intrinsics)
        ax.scatter(uv[:, 0], uv[:, 1], s=0.3, c="tab:green" if correct else "tab:red", alpha=0.5)
    ax.set_title(scene.title, fontsize=8)
    ax.axis("off")


def plot(data: dict, scenes: list[DrawnScene], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    splits = list(data["splits"])
    fig = plt.figure(figsize=(16, 9))
    grid = fig.add_gridspec(2, max(3, len(scenes)))
    for k, name in enumerate(splits):
        _recall_bars(fig.add_subplot(grid[0, k]), data["splits"][name], name)
    _times(fig.add_subplot(grid[0, len(splits)]), data)
    for k, scene in enumerate(scenes):
        _scene(fig.add_subplot(grid[1, k]), scene)
    fig.text(0.5, 0.01, "scenes: true poses of found parts blue, of missed ones gold; psorr's correct detections "
             "green, false ones red", ha="center", fontsize=9)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    fig.savefig(path, dpi=90)
    plt.close(fig)
