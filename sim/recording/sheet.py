"""The contact sheet of a recorded episode (:mod:`sim.recording.recorder`): a row per look, the models drawn on it at
the poses the look returned, and the PNG they make."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.world import World


@dataclass(frozen=True, eq=False)
class ModelOverlay:
    """One model drawn on a look's depth image: its name, score and pixels (N, 2) (u right, v down)."""

    name: str
    score: float
    pixels: np.ndarray


@dataclass(eq=False)
class SheetRow:
    """One look on the contact sheet, and the grasp that followed it.

    Attributes:
        look: 1-based index of the look in the episode; sim_s: its simulated time (s).
        rgb: (H, W, 3) uint8 Kinect view.
        depth_shade: (H, W) float32 in [0, 1] grey of the depth cloud by height above the table (dark: tall;
            white: no return or below the table), None for oracle looks.
        overlays: the models at the poses the look returned (recognised, or the truth for the oracle).
        grasp: (PANEL_H, PANEL_W, 3) uint8 close-up of the gripper at its grasp (a video panel of
            :mod:`sim.recording.recorder`), None when none followed.
        grasp_part: the part grasped ("" when none).
    """

    look: int
    sim_s: float
    rgb: np.ndarray
    depth_shade: np.ndarray | None
    overlays: tuple[ModelOverlay, ...]
    grasp: np.ndarray | None = None
    grasp_part: str = ""


def height_shade(frame, table_top: float) -> np.ndarray:
    """(H, W) grey in [0, 1] of a Kinect frame's cloud by height above the table: the table light, anything
    standing on it darker the taller it is, below the table and no return white.

    Height, not depth: across the tilted table depth changes by ~0.3 m, which would drown a 2 cm part.
    """
    cloud, T = frame.cloud, frame.T_world_camera
    height = (cloud.points @ T[2, :3] + T[2, 3] - table_top).reshape(cloud.height, cloud.width)
    height = np.nan_to_num(height, nan=-1.0)
    # 3 mm of dead band hides the sensor's noise on the table; 3 cm and taller is darkest.
    shade = 0.85 - 0.75 * np.clip((height - 0.003) / 0.03, 0.0, 1.0)
    return np.where(height > -0.02, shade, 1.0).astype(np.float32)


def project_points(points: np.ndarray, T_camera_model: np.ndarray, world: World, scale: float) -> np.ndarray:
    """Pixels (N, 2) of model points (N, 3) at ``T_camera_model`` (OpenCV camera frame) in an image
    ``scale`` times the camera's size; points behind the camera are dropped."""
    cam = points @ T_camera_model[:3, :3].T + T_camera_model[:3, 3]
    cam = cam[cam[:, 2] > 1e-3]
    k = world.config.intrinsics
    u, v = k.fx * cam[:, 0] / cam[:, 2] + k.cx, k.fy * cam[:, 1] / cam[:, 2] + k.cy
    return scale * np.column_stack([u + 0.5, v + 0.5]) - 0.5  # scale about pixel corners, not centres


def write_sheet(path: Path, rows: list[SheetRow], title: str) -> None:
    """Rows of (Kinect RGB, depth with models, grasp close-up); models drawn as psorr.viz.render draws detections."""
    import matplotlib

    matplotlib.use("Agg")  # headless: the sheet goes to a file, never to a window
    import matplotlib.pyplot as plt

    cmap = plt.get_cmap("tab10")
    # One colour per model name across the sheet, so a part keeps its colour from row to row.
    colour = {n: cmap(i % 10) for i, n in enumerate(dict.fromkeys(o.name for r in rows for o in r.overlays))}
    fig, axes = plt.subplots(max(1, len(rows)), 3, figsize=(9.6, 2.55 * max(1, len(rows)) + 0.6), dpi=100,
                             squeeze=False)
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax_row, row in zip(axes, rows):
        rgb_ax, depth_ax, grasp_ax = ax_row
        if row.look:
            rgb_ax.imshow(row.rgb)
            rgb_ax.set_title(f"look {row.look} at {row.sim_s:.1f} s", fontsize=8)
            h, w = row.rgb.shape[:2]
            if row.depth_shade is not None:
                depth_ax.imshow(row.depth_shade, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
            else:
                depth_ax.imshow(row.rgb, alpha=0.4)
            for overlay in row.overlays:
                u, v = overlay.pixels.T
                depth_ax.scatter(u, v, s=0.6, color=colour[overlay.name], linewidths=0, alpha=0.8)
                if len(u):
                    depth_ax.annotate(f"{overlay.name} {overlay.score:.2f}", (np.median(u), v.min()),
                                      color=colour[overlay.name], fontsize=7, ha="center", va="bottom", weight="bold")
            depth_ax.set_xlim(0, w)
            depth_ax.set_ylim(h, 0)
            kind = "depth (dark: high), recognised" if row.depth_shade is not None else "oracle: true poses"
            depth_ax.set_title(f"{kind} ({len(row.overlays)})", fontsize=8)
        if row.grasp is not None:
            grasp_ax.imshow(row.grasp)
            grasp_ax.set_title(f"grasped {row.grasp_part}", fontsize=8)
        else:
            grasp_ax.text(0.5, 0.5, "no grasp after this look", ha="center", va="center", fontsize=8,
                          color="0.5", transform=grasp_ax.transAxes)
    if not rows:
        axes[0, 1].text(0.5, 0.5, "no look got past the person", ha="center", va="center", fontsize=9,
                        transform=axes[0, 1].transAxes)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path)  # the directory was checked when the recorder was made
    plt.close(fig)
