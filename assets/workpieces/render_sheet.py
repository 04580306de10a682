"""Overview picture of the workpieces for people: one shaded 3-D view per part, in its catalog colour."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless: no display on build machines

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

LIGHT = np.array([0.4, -0.5, 0.77])  # from the viewer's upper left, so tops are brighter than sides


def _shade(mesh, color) -> np.ndarray:
    """(F, 4) per-face RGBA: Lambert shading with an ambient floor so faces turned away stay readable."""
    lambert = np.clip(mesh.face_normals @ (LIGHT / np.linalg.norm(LIGHT)), 0.0, 1.0)
    rgb = np.clip(np.outer(0.35 + 0.65 * lambert, color), 0.0, 1.0)
    return np.column_stack([rgb, np.ones(len(rgb))])


def render_sheet(parts: dict, path: Path, columns: int = 4) -> None:
    """Write a PNG grid of `parts` (name -> Part from build_workpieces), titled with name and size in mm."""
    rows = math.ceil(len(parts) / columns)
    fig = plt.figure(figsize=(4.2 * columns, 4.0 * rows), dpi=110)
    for index, part in enumerate(parts.values()):
        ax = fig.add_subplot(rows, columns, index + 1, projection="3d")
        # matplotlib depth-sorts whole triangles by centroid; long CAD slivers sort wrongly, small ones do not.
        vertices, faces = trimesh.remesh.subdivide_to_size(part.mesh.vertices, part.mesh.faces, part.mesh.scale / 40)
        mesh = trimesh.Trimesh(vertices, faces, process=False)
        colors = _shade(mesh, part.color)
        triangles = mesh.vertices[mesh.faces] * 1000.0
        ax.add_collection3d(Poly3DCollection(triangles, facecolors=colors, edgecolors=colors, linewidths=0.3))
        lo, hi = mesh.bounds * 1000.0
        centre, half = (lo + hi) / 2, (hi - lo).max() / 2
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_zlim(centre[2] - half, centre[2] + half)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=35, azim=-58)
        ax.set_xlabel("x mm", fontsize=7, labelpad=-4)
        ax.set_ylabel("y mm", fontsize=7, labelpad=-4)
        ax.tick_params(labelsize=6, pad=-2)
        size = " x ".join(f"{e:.0f}" for e in hi - lo)
        ax.set_title(f"{part.name}\n{size} mm", fontsize=10)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
