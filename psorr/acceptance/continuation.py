"""Does the measured surface go on past a pose's outline? Then the object there is larger than the model.

The point check asks whether the surface a pose would show is measured and not seen through. A part
made of plates passes it wherever another object shows the same plates: an L bracket fitted into a
box's corner, a chassis on a box's top (the OSD learn set's boxes took 43 such detections over 45
clouds). What tells them apart lies just outside the model: there the box's faces go on, in the
planes of the model's faces, where a real bracket's outline would show the table or a gap.

The check looks at a ring of pixels around the pose's silhouette (the posed mesh rendered, and every
posed model point's pixel, gaps between samples closed), where the outline is in view (beside model points the
sensor measures, not beside an occluder), and asks, for each measured ring pixel off the supporting
plane, whether it lies on the tangent plane of one of the visible model points nearest it in space. One
nearest point is not enough: past a bracket's leg the nearest points are on the leg's 5 mm top edge,
whose plane is across the box face that goes on above the leg, and the leg's own face is a few
millimetres further. The supporting plane is left out, by the sensor's noise: a part lying flat on the
table continues the table's plane by design. A pixel beside the outline may read the model's own face
through the sensor's lateral jitter; it counts only what it shows beyond that chance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import binary_closing, binary_dilation, correlate
from scipy.spatial import cKDTree

from psorr.checks import params as check
from psorr.sensing.noise_context import depth_noise
from psorr.verification.depth_compare import DepthRenderer
from psorr.verification.lateral_jitter import jitter_offsets
from psorr.verification.point_check import CheckParams, depth_tolerance, visible_model_points
from psorr.verification.scene_view import SceneView


@dataclass(frozen=True)
class ContinuationParams:
    """``ring`` metres of outline around a pose are looked at; a ring point within the depth tolerance
    (``check``) of the tangent plane of one of the ``neighbours`` visible model points nearest it, and off the
    supporting plane, continues the model's surface. Off the plane is higher than the sensor's noise lifts
    ``table_share`` of the plane's own points (a one-sided Gaussian bar on the sensor model's height sigma at
    the point), and at least ``off_support`` metres, the bar of a sensor without noise. At most
    ``max_points`` model points are tested for what shows and give tangent planes; the silhouette takes every one."""

    ring: float = 0.01
    neighbours: int = 16
    table_share: float = 0.01
    off_support: float = 0.001
    max_points: int = 6000
    check: CheckParams = CheckParams()

    def __post_init__(self):
        check.positive(self, "ring", unit=" metres")
        check.non_negative(self, "off_support", unit=" metres")
        check.within(self, "table_share", closed=False)
        check.whole(self, "neighbours", "max_points")
        check.instance(self, "check", CheckParams)


def continued_share(view: SceneView, model_points: np.ndarray, model_normals: np.ndarray, T_cloud_model: np.ndarray,
                    params: ContinuationParams = ContinuationParams(), renderer: DepthRenderer | None = None) -> float:
    """Share in [0, 1] of the measured pixels in a ring around the pose's silhouette whose point continues a
    face of the model beyond the chance that the sensor's jitter read the model itself there (see the module
    docstring); 0 when the pose shows nothing. The silhouette is the samples', and with the model's mesh
    ``renderer`` the rendered mesh's too."""
    stride = max(1, len(model_points) // params.max_points)
    R, t = T_cloud_model[:3, :3], T_cloud_model[:3, 3]
    posed = model_points @ R.T + t
    pts, nrm = posed[::stride], model_normals[::stride] @ R.T
    visible = visible_model_points(view, pts, nrm)
    if len(visible) == 0:
        return 0.0
    # The outline is the whole model's, not only of what shows: a coil that hides the core behind it
    # leaves holes in the visible points' pixels, and the core seen through them would count as going on.
    # And of every sample: a large part's thinned samples leave gaps in its silhouette wider than the
    # closing closes (a 300 mm tray's face went on through them over half the ring).
    every_u, every_v, inside = view.project(posed)
    u, v = every_u[visible], every_v[visible]
    z = float(np.median(pts[visible, 2]))
    reach = max(1, int(round(params.ring * view.focal / z)))
    # Work in a window around the silhouette: the whole buffer would cost more than the check itself.
    pad = reach + 3
    u0, v0 = max(int(u.min()) - pad, 0), max(int(v.min()) - pad, 0)
    u1, v1 = min(int(u.max()) + pad + 1, view.width), min(int(v.max()) + pad + 1, view.height)
    shape = (v1 - v0, u1 - u0)
    covered = np.zeros(shape, dtype=bool)
    in_window = inside & (every_u >= u0) & (every_u < u1) & (every_v >= v0) & (every_v < v1)
    covered[every_v[in_window] - v0, every_u[in_window] - u0] = True
    silhouette = binary_closing(covered, iterations=2)  # the visible points are among them
    if renderer is not None:
        silhouette |= _rendered_silhouette(view, renderer, T_cloud_model, (u0, v0), shape)
    ring = binary_dilation(silhouette, iterations=reach) & ~silhouette
    ring &= _around_measured(view, pts[visible], u, v, (u0, v0), shape, reach, params)
    rv, ru = np.nonzero(ring)
    depth = view.depth[(rv + v0) * view.width + (ru + u0)]
    measured = np.isfinite(depth)
    if not measured.any():
        return 0.0
    rv, ru, depth = rv[measured], ru[measured], depth[measured]
    own = _own_read_chance(silhouette)[rv, ru]
    q = np.column_stack([(ru + u0 - view.cx) * depth / view.focal, (rv + v0 - view.cy) * depth / view.focal, depth])
    # The default 16 nearest of the ~1 mm spaced samples span about 4 mm: past an edge face they take in
    # the faces it joins. Thinned samples keep that span with fewer: 16 of every fifth of a 300 mm tray's
    # reached its top face's plane from beyond its walls, where other parts stood as high as it.
    neighbours = max(1, round(params.neighbours / stride))
    _, nearest = cKDTree(pts[visible]).query(q, k=min(neighbours, len(visible)))
    nearest = visible[nearest.reshape(len(q), -1)]
    off_plane = np.abs(np.einsum("ijk,ijk->ij", q[:, None] - pts[nearest], nrm[nearest]))
    on_face = (off_plane < depth_tolerance(depth, params.check)[:, None]).any(axis=1)
    if view.support_plane is not None:
        on_face &= q @ view.support_plane[:3] + view.support_plane[3] > _off_support_bar(q, view.support_plane, params)
    # A ring pixel beside the outline reads the model's own face with the jitter's chance ``own``, and that reading
    # goes on past the outline by itself: each pixel counts what it shows beyond that chance, so a true pose's
    # band beside the outline adds nothing on average, and a larger object's, which goes on whatever it reads, all.
    return max(0.0, float(np.mean((on_face - own) / (1.0 - own))))


def _off_support_bar(points: np.ndarray, plane: np.ndarray, params: ContinuationParams) -> np.ndarray:
    """(N,) the height (m) over the supporting ``plane`` past which each ring point (N, 3) is off it: where the
    sensor's noise lifts ``table_share`` of the plane's own points. A part lying flat continues the table's
    plane by design, and a thin one's top face lies within the depth tolerance of the table, so every table
    point this bar lets through counts as going on: the bar keeps them to a tenth of the share that drops a pose."""
    return np.maximum(params.off_support, depth_noise().height_lifted(points, plane[:3], params.table_share))


def _rendered_silhouette(view: SceneView, renderer: DepthRenderer, T_cloud_model: np.ndarray,
                         corner: tuple[int, int], shape: tuple[int, int]) -> np.ndarray:
    """(``shape``) bool: the window's pixels (from ``corner`` u0, v0) whose ray meets the posed mesh. Samples
    fall short of the outline by up to half their spacing, which a sensor of fine pixels sees: at 1280x720 a
    bracket's 5 mm base, read one or two pixels past its samples, went on past its own outline. A pixel a
    sample falls in is covered too, though its centre's ray may miss: a pose a millimetre off shifts a
    millimetre-pixel outline by a pixel, and the rendered outline alone then put true poses past the bar."""
    u0, v0 = corner
    V, U = np.mgrid[v0:v0 + shape[0], u0:u0 + shape[1]]
    depth = renderer.depth(T_cloud_model[None], view.rays(U.ravel(), V.ravel()))[0]
    return np.isfinite(depth).reshape(shape)


def _own_read_chance(silhouette: np.ndarray) -> np.ndarray:
    """(H, W) the chance that the sensor's lateral jitter takes each pixel's sample inside the ``silhouette``
    (H, W) bool (:func:`psorr.verification.lateral_jitter.jitter_offsets`); 0 for a sensor without jitter."""
    offsets, weights = jitter_offsets(depth_noise())
    reach = int(np.abs(offsets).max())
    kernel = np.zeros((2 * reach + 1, 2 * reach + 1))
    kernel[offsets[:, 1] + reach, offsets[:, 0] + reach] = weights
    return correlate(silhouette.astype(float), kernel, mode="constant")


def _around_measured(view: SceneView, points: np.ndarray, u: np.ndarray, v: np.ndarray, corner: tuple[int, int],
                     shape: tuple[int, int], reach: int, params: ContinuationParams) -> np.ndarray:
    """The window's pixels (``shape``, from ``corner`` u0, v0) within ``reach`` of where the visible model
    ``points`` (at pixels ``u``, ``v``) are measured, and the 2 pixels by which the silhouette's closing
    may reach past them. Only there does the outline show: where something
    nearer hides the model, what lies around its outline is that occluder, whose surface may well cross
    the planes of the model's faces (an arm across a chassis's walls)."""
    u0, v0 = corner
    measured = np.abs(points[:, 2] - view.depth[v * view.width + u]) < depth_tolerance(points[:, 2], params.check)
    shown = np.zeros(shape, dtype=bool)
    shown[v[measured] - v0, u[measured] - u0] = True
    return binary_dilation(binary_closing(shown, iterations=2), iterations=reach + 2)


def on_larger_object(view: SceneView, model_points: np.ndarray, model_normals: np.ndarray, T_cloud_model: np.ndarray,
                     max_continued: float | None, params: ContinuationParams,
                     renderer: DepthRenderer | None = None) -> bool:
    """Does the measured surface go on past the pose's outline, in its faces' planes, on more than
    ``max_continued`` of the ring (:func:`continued_share`)? An L bracket in a box's corner passes every check on
    the surface it would show; the box's faces beyond its legs do not. Never, with max_continued None.
    1-5 ms a pose: recognition asks it only of the candidates it would accept."""
    return max_continued is not None and continued_share(
        view, model_points, model_normals, T_cloud_model, params, renderer) > max_continued
