"""Pictures of decompositions: the cloud coloured by primitive, cylinders in
reds and planes in blue-greens (as in the paper's Fig. 6), with the primitive
shape graph drawn between centroids."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless: pictures go to files, never to a window
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from psorr.types import PointCloud, PrimitiveKind, PrimitiveShapeGraph  # noqa: E402

UNLABELLED_RGB = (0.78, 0.78, 0.78)


def primitive_colors(graph: PrimitiveShapeGraph) -> np.ndarray:
    """(P, 3) RGB per primitive: planes spread over blue-greens, cylinders over reds."""
    colors = np.zeros((len(graph), 3))
    planes = [i for i, p in enumerate(graph.primitives) if p.kind is PrimitiveKind.PLANE]
    cylinders = [i for i, p in enumerate(graph.primitives) if p.kind is PrimitiveKind.CYLINDER]
    # Alternate ends of the ramp so neighbours in index order differ visibly.
    for indices, cmap, lo, hi in ((planes, plt.get_cmap("GnBu"), 0.35, 1.0),
                                  (cylinders, plt.get_cmap("Reds"), 0.35, 1.0)):
        if not indices:
            continue
        ramp = np.linspace(lo, hi, len(indices))
        ramp = np.concatenate([ramp[0::2], ramp[1::2][::-1]])
        for i, t in zip(indices, ramp):
            colors[i] = cmap(t)[:3]
    return colors


def _project(points: np.ndarray, width: int, height: int):
    """Pinhole projection from the sensor origin, scaled so the cloud fills the image."""
    z = np.maximum(points[:, 2], 1e-6)
    u, v = points[:, 0] / z, points[:, 1] / z
    scale = 0.95 * min(width / max(np.ptp(u), 1e-9), height / max(np.ptp(v), 1e-9))
    cu, cv = (u.max() + u.min()) / 2, (v.max() + v.min()) / 2
    return scale * (u - cu) + width / 2, scale * (v - cv) + height / 2


def label_image(cloud: PointCloud, labels: np.ndarray, graph: PrimitiveShapeGraph,
                width: int = 640, height: int = 480) -> tuple[np.ndarray, np.ndarray]:
    """RGB image (H, W, 3) of the cloud coloured by label, and the pixel of each point (N, 2)."""
    return painted(cloud, labels, primitive_colors(graph), width, height)


def painted(cloud: PointCloud, labels: np.ndarray, colors: np.ndarray, width: int = 640,
            height: int = 480) -> tuple[np.ndarray, np.ndarray]:
    """RGB image (H, W, 3) of the cloud, each point in its label's row of colors (L, 3) (label -1 grey),
    and the pixel of each point (N, 2)."""
    colors = np.vstack([colors, UNLABELLED_RGB])  # label -1 -> last row
    valid = cloud.valid_mask
    if cloud.is_organised:
        width, height = cloud.width, cloud.height
        rows, cols = np.divmod(np.arange(len(cloud)), width)
        px = np.column_stack([cols, rows]).astype(float)
    else:
        px = np.full((len(cloud), 2), np.nan)
        px[valid, 0], px[valid, 1] = _project(cloud.points[valid], width, height)
    image = np.ones((height, width, 3))
    idx = np.flatnonzero(valid)
    # Far points first, so nearer ones overwrite them (a painter's z-buffer).
    idx = idx[np.argsort(-cloud.points[idx, 2], kind="stable")]
    cols = np.clip(px[idx, 0].round().astype(int), 0, width - 1)
    rows = np.clip(px[idx, 1].round().astype(int), 0, height - 1)
    image[rows, cols] = colors[labels[idx]]
    return image, px


def save_decomposition_png(path, cloud: PointCloud, labels: np.ndarray, graph: PrimitiveShapeGraph,
                           title: str = "") -> Path:
    """Write the labelled cloud with the shape graph drawn over it."""
    path = Path(path)
    image, px = label_image(cloud, labels, graph)
    h, w = image.shape[:2]
    fig, ax = plt.subplots(figsize=(w / 80, h / 80 + 0.6), dpi=80)
    ax.imshow(image, interpolation="nearest")
    centres = []
    for prim in graph.primitives:
        members = prim.inliers[np.isfinite(px[prim.inliers]).all(axis=1)]
        centres.append(np.median(px[members], axis=0) if len(members) else (np.nan, np.nan))
    centres = np.array(centres).reshape(-1, 2)
    for i, j in graph.edges:
        ax.plot(*centres[[i, j]].T, color="black", linewidth=0.8, alpha=0.6)
    for i, prim in enumerate(graph.primitives):
        mark = "s" if prim.kind is PrimitiveKind.PLANE else "o"
        ax.plot(*centres[i], mark, color="white", markeredgecolor="black", markersize=7)
        ax.annotate(str(i), centres[i], fontsize=7, ha="center", va="center")
    n_planes = graph.count(PrimitiveKind.PLANE)
    ax.set_title(title or f"{n_planes} planes (blue-green), {len(graph) - n_planes} cylinders (red), "
                 f"{len(graph.edges)} graph edges", fontsize=9)
    ax.set_axis_off()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return path


def _image_size(cloud: PointCloud) -> tuple[int, int]:
    """Width and height in pixels of the sensor's view of ``cloud``: its grid's, or a Kinect's 640x480."""
    return (cloud.width, cloud.height) if cloud.is_organised else (640, 480)


def draw_detections(ax, cloud: PointCloud, detections, library,
                    point_size: float = 0.3) -> tuple[int, int, list[np.ndarray]]:
    """Draw the cloud in grey on ``ax``, seen from the sensor (dots of ``point_size`` points squared: larger
    for a view cropped to a part), with each detected model's surface samples in its own colour at the
    recognised pose. Returns the image's width and height in pixels and, per
    detection, its samples' pixels (N, 2): what a caller needs to crop the view to them."""
    valid = cloud.valid_mask
    pts = cloud.points[valid]
    w, h = _image_size(cloud)
    if cloud.is_organised:
        rows, cols = np.divmod(np.flatnonzero(valid), cloud.width)
        f = 525.0
        # Recover the pinhole from the organised grid, so model points land on their pixels.
        cx = float(np.median(cols - f * pts[:, 0] / pts[:, 2]))
        cy = float(np.median(rows - f * pts[:, 1] / pts[:, 2]))
    else:
        f = None
    if f is None:
        u, v = _project(pts, w, h)
    else:
        u, v = f * pts[:, 0] / pts[:, 2] + cx, f * pts[:, 1] / pts[:, 2] + cy
    shade = np.clip(1.2 - pts[:, 2] / max(pts[:, 2].max(), 1e-6), 0.2, 0.9)
    ax.scatter(u, v, c=shade, cmap="gray", s=point_size, linewidths=0, vmin=0, vmax=1)
    cmap = plt.get_cmap("tab10")
    drawn = []
    for k, det in enumerate(detections):
        model = library.model(det.model)
        mp = model.points[:: max(1, len(model.points) // 3000)]
        cam = mp @ det.T_cloud_model[:3, :3].T + det.T_cloud_model[:3, 3]
        if f is None:
            mu, mv = _project(np.vstack([pts, cam]), w, h)
            mu, mv = mu[len(pts):], mv[len(pts):]
        else:
            mu, mv = f * cam[:, 0] / cam[:, 2] + cx, f * cam[:, 1] / cam[:, 2] + cy
        ax.scatter(mu, mv, s=1.5, color=cmap(k % 10), linewidths=0, alpha=0.8)
        ax.annotate(f"{det.model} {det.score:.2f}", (np.median(mu), mv.min()), color=cmap(k % 10), fontsize=8,
                    ha="center", va="bottom", weight="bold", bbox=dict(facecolor="white", alpha=0.7, linewidth=0))
        drawn.append(np.column_stack([mu, mv]))
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)
    ax.set_aspect("equal")
    ax.set_axis_off()
    return w, h, drawn


def save_detections_png(path, cloud: PointCloud, detections, library) -> Path:
    """The cloud in grey with each detected model's surface samples drawn in
    its own colour at the recognised pose, seen from the sensor."""
    path = Path(path)
    w, h = _image_size(cloud)
    fig, ax = plt.subplots(figsize=(w / 80, h / 80 + 0.6), dpi=80)
    draw_detections(ax, cloud, detections, library)
    ax.set_title(f"{len(detections)} detections", fontsize=9)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return path


def save_segmentation_png(path, cloud: PointCloud, labels: np.ndarray, segments, title: str = "") -> Path:
    """Write the cloud with each segment (psorr.segment.Segment) in a colour of its own, numbered and
    named by its colour, beside the cloud's own colours when it has them."""
    path = Path(path)
    own = np.array([plt.get_cmap("tab20")(k % 20)[:3] for k in range(len(segments))]).reshape(-1, 3)
    image, px = painted(cloud, labels, own)
    h, w = image.shape[:2]
    panels = [image] if cloud.colors is None else [_true_colours(cloud), image]
    fig, axes = plt.subplots(1, len(panels), figsize=(len(panels) * w / 80, h / 80 + 0.6), dpi=80, squeeze=False)
    for ax, panel in zip(axes[0], panels):
        ax.imshow(panel, interpolation="nearest")
        ax.set_axis_off()
    for seg in segments:
        members = np.flatnonzero(labels == seg.id)
        members = members[np.isfinite(px[members]).all(axis=1)]
        if len(members):
            axes[0, -1].annotate(f"{seg.id} {seg.colour or ''}", np.median(px[members], axis=0), fontsize=8,
                                 ha="center", va="center", bbox={"fc": "white", "alpha": 0.7, "lw": 0})
    axes[0, -1].set_title(title or f"{len(segments)} segments", fontsize=9)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return path


def _true_colours(cloud: PointCloud) -> np.ndarray:
    """The cloud drawn in its own colours, laid out as painted() lays it out: each point its own label."""
    coloured = np.isfinite(cloud.colors).all(axis=1)
    return painted(cloud, np.where(coloured, np.arange(len(cloud)), -1), np.nan_to_num(cloud.colors))[0]
