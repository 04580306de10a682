"""Render and compare: a model's depth image at candidate poses against the measured depth.

Primitive boxes and sampled points judge a pose by the surface the model has. Neither notices a
feature that is *missing*: the turned flange is solid where the scene shows a bolt hole, and the
tray turned end for end has its connector window in the wrong end wall. Ray casting the model's
mesh through the pixels of the scene's depth buffer, with the supporting plane behind it,
predicts what the sensor measures at every pixel, holes included. The residual against the
measurement then tells such poses apart.
"""

from __future__ import annotations

import numpy as np
import open3d as o3d
from scipy.ndimage import binary_dilation

from psorr.sensing.noise_context import depth_noise
from psorr.verification.lateral_jitter import jitter_offsets, mixture_costs, own_pixel
from psorr.verification.scene_view import SceneView

RESIDUAL_CAP = 9.0  # squared sigmas: one pixel that disagrees costs at most a 3-sigma miss
DISCRIMINATIVE_SIGMAS = 3.0  # pixels where the candidates' renders differ by more than this tell them apart
# A coarse search's poses, a sweep apart, need no more pixels than this across the sweep to tell which is
# nearest: a large part 0.6 m away ran its 90 turns over every one of 114,000 pixels (docs/decisions/0076).
SAMPLES_PER_SWEEP = 4


class DepthRenderer:
    """Renders one model's mesh (metres, model frame) into a :class:`SceneView`'s pixels.

    Args:
        vertices: (V, 3) mesh vertices, metres.
        faces: (F, 3) triangle vertex indices.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray):
        self._scene = o3d.t.geometry.RaycastingScene()
        self._scene.add_triangles(o3d.core.Tensor(np.asarray(vertices, dtype=np.float32)),
                                  o3d.core.Tensor(np.asarray(faces, dtype=np.uint32)))

    def depth(self, poses: np.ndarray, rays: np.ndarray) -> np.ndarray:
        """(K, P) depth (z in the cloud frame, metres; inf where the ray misses) of the model at each
        of ``poses`` (K, 4, 4) ``T_cloud_model`` along ``rays`` (P, 3) from the origin with z = 1."""
        poses = np.asarray(poses).reshape(-1, 4, 4)
        batch = np.empty((len(poses), len(rays), 6), dtype=np.float32)
        for k, T in enumerate(poses):
            _model_frame_rays(T, rays, batch[k])
        hit = self._scene.cast_rays(o3d.core.Tensor(batch.reshape(-1, 6)))["t_hit"].numpy()
        # A direction with z = 1 makes the ray parameter the depth itself.
        return hit.reshape(len(poses), len(rays)).astype(np.float64)

    def surface(self, T_cloud_model: np.ndarray, rays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where ``rays`` (P, 3) from the origin with z = 1 meet the model at ``T_cloud_model`` (4, 4): the
        (P,) depth (inf where a ray misses) and the (P, 3) unit normal of the face hit, in the cloud frame
        (NaN where a ray misses)."""
        batch = _model_frame_rays(T_cloud_model, rays, np.empty((len(rays), 6), dtype=np.float32))
        hit = self._scene.cast_rays(o3d.core.Tensor(batch))
        normals = hit["primitive_normals"].numpy().astype(np.float64) @ T_cloud_model[:3, :3].T
        depth = hit["t_hit"].numpy().astype(np.float64)
        normals[~np.isfinite(depth)] = np.nan
        return depth, normals

    def distance(self, points: np.ndarray) -> np.ndarray:
        """(N,) unsigned distance (metres) from model-frame ``points`` (N, 3) to the mesh."""
        return self._scene.compute_distance(o3d.core.Tensor(np.asarray(points, dtype=np.float32))).numpy()


def _model_frame_rays(T_cloud_model: np.ndarray, rays: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``out`` (P, 6) filled with ``rays`` (P, 3) from the sensor origin as Open3D casts them against a mesh at
    ``T_cloud_model``: the origin, then each direction, in the model frame."""
    R, t = T_cloud_model[:3, :3], T_cloud_model[:3, 3]
    out[:, :3] = -R.T @ t  # the sensor origin in the model frame
    out[:, 3:] = rays @ R  # each ray's direction, rotated into the model frame
    return out


def footprint(view: SceneView, points: np.ndarray, spacing: float) -> np.ndarray:
    """(height x width,) bool: the pixels a surface sampled by ``points`` (N, 3), cloud frame, every ``spacing``
    m or closer, can cover: each point's pixel and those within the spacing of it, and a pixel more."""
    u, v, inside = view.project(points)
    covered = np.zeros((view.height, view.width), dtype=bool)
    covered[v[inside], u[inside]] = True
    if inside.any():
        reach = int(np.ceil(view.focal * spacing / max(float(points[inside, 2].min()), 1e-3))) + 1
        covered = binary_dilation(covered, iterations=reach)
    return covered.ravel()


def pixel_window(view: SceneView, centre: np.ndarray, radius: float, sweep: float = 0.0,
                 within: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The measured pixels of ``view`` around a sphere (``centre`` (3,), cloud frame; ``radius`` m):
    flat pixel indices (P,) and their rays (P, 3) with z = 1. A search whose poses lie ``sweep`` m apart
    where they differ most takes every k-th pixel in u and v, SAMPLES_PER_SWEEP of them across a sweep.
    ``within``: only the pixels it marks (:func:`footprint`; flat, height x width)."""
    pixels, U, V = _window_pixels(view, centre, radius, sweep, within)
    return pixels, view.rays(U, V)


def _window_pixels(view: SceneView, centre: np.ndarray, radius: float, sweep: float,
                   within: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`pixel_window`: the flat indices (P,), columns (P,) and rows (P,)."""
    z = max(float(centre[2]) - radius, 1e-3)
    u0 = view.focal * centre[0] / centre[2] + view.cx
    v0 = view.focal * centre[1] / centre[2] + view.cy
    reach = view.focal * radius / z + 2
    stride = max(1, int(view.focal * sweep / z / SAMPLES_PER_SWEEP))
    us = np.arange(max(0, int(u0 - reach)), min(view.width, int(u0 + reach) + 1), stride)
    vs = np.arange(max(0, int(v0 - reach)), min(view.height, int(v0 + reach) + 1), stride)
    U, V = np.meshgrid(us, vs)
    pixels = (V * view.width + U).ravel()
    measured = np.isfinite(view.depth[pixels])
    if within is not None:
        measured &= within[pixels]
    return pixels[measured], U.ravel()[measured], V.ravel()[measured]


def residual_costs(view: SceneView, renderer: DepthRenderer, poses: np.ndarray, centre: np.ndarray,
                   radius: float, discriminative: bool = True, sweep: float = 0.0,
                   within: np.ndarray | None = None) -> np.ndarray:
    """(K,) cost of each pose (K, 4, 4): the summed squared depth residual, in the sensor's sigmas and
    capped at ``RESIDUAL_CAP``, of the rendered model (with the supporting plane behind it) against
    the measured depth, over the pixels around the sphere (``centre``, ``radius``).

    With ``discriminative``, only pixels where some pose renders differently from the first count:
    the rest add the same amount to every pose, and their noise would drown a small feature. ``sweep`` and
    ``within``: as :func:`pixel_window` takes them; pixels that no pose covers add the same to every cost.
    """
    window = _window_costs(view, centre, radius, lambda rays: renderer.depth(poses, rays), sweep, within)
    if window is None:
        return np.zeros(len(poses))
    cost, rendered, sigma = window
    if discriminative:
        cost = cost[:, differs(rendered, rendered[:1], sigma).any(axis=0)]
    return cost.sum(axis=1)


def twin_costs(view: SceneView, renderer: DepthRenderer, poses: np.ndarray, twins: list[tuple[int, int]],
               centre: np.ndarray, radius: float, within: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(K,) cost of each pose (K, 4, 4), as :func:`residual_costs`, over the pixels around the sphere where
    some pose a of the ``twins`` pairs (a, b) of indices into ``poses`` renders differently from its twin b
    by more than the sensor's sigma, each pixel weighted by how much it tells: the squared gap between the
    renders in sigmas, capped as a residual is, over the cap (1 at the discrimination bar and beyond); and
    (len(twins),) each pair's evidence: those squared gaps summed, what the wrong one of a pair costs above
    the right one in expectation. ``within``: as :func:`pixel_window` takes it (the pixels the poses can cover)."""
    window = _window_costs(view, centre, radius, lambda rays: renderer.depth(poses, rays), within=within)
    if window is None:
        return np.zeros(len(poses)), np.zeros(len(twins))
    cost, rendered, sigma = window
    a, b = np.array(twins).T
    told = _told(rendered[a], rendered[b], sigma)
    return (cost * (told.max(axis=0) / RESIDUAL_CAP)[None]).sum(axis=1), told.sum(axis=1)


def _told(rendered: np.ndarray, other: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """(K, P) what each pixel tells between the depths ``rendered`` (K or 1, P) and ``other`` (K, P): the
    squared gap in the sensor's ``sigma`` (P,), capped as a residual is, where it exceeds one sigma (or where
    one render hits the model and the other does not); 0 elsewhere."""
    hits = np.isfinite(rendered) != np.isfinite(other)
    with np.errstate(invalid="ignore"):
        gap = np.where(hits, np.inf, np.nan_to_num(np.abs(rendered - other) / sigma[None], nan=0.0))
    # At a pixel where the renders differ by one sigma, the wrong pose's expected cost (1 + gap^2) is twice the
    # right one's; below that a pixel tells little, and its noise would only dilute those that tell much.
    return np.where(gap > 1.0, np.minimum(gap**2, RESIDUAL_CAP), 0.0)


def rival_costs(view: SceneView, rivals: list[tuple[DepthRenderer, np.ndarray]], centre: np.ndarray,
                radius: float) -> tuple[np.ndarray, int, float]:
    """(K,) cost of each of K ``rivals`` (a model's renderer and its pose ``T_cloud_model``; different models
    may compete), as :func:`residual_costs`, over the pixels around the sphere (``centre``, ``radius``) where
    some rival renders differently from the first; how many pixels those are; and the evidence, as in
    :func:`twin_costs`: the capped squared gaps, in sigmas, between the renders summed over the pixels where
    some rival differs from the first by more than one sigma."""
    window = _window_costs(view, centre, radius,
                           lambda rays: np.vstack([r.depth(T[None], rays) for r, T in rivals]))
    if window is None:
        return np.zeros(len(rivals)), 0, 0.0
    cost, rendered, sigma = window
    telling = differs(rendered, rendered[:1], sigma).any(axis=0)
    evidence = float(_told(rendered[:1], rendered[1:], sigma).max(axis=0).sum())
    return cost[:, telling].sum(axis=1), int(telling.sum()), evidence


def table_costs(view: SceneView, renderer: DepthRenderer, T_cloud_model: np.ndarray, centre: np.ndarray,
                radius: float) -> tuple[np.ndarray, int]:
    """(2,) costs, as :func:`residual_costs`, of the model at ``T_cloud_model`` with the supporting plane
    behind it and of the bare plane, over the pixels around the sphere (``centre``, ``radius``) where the
    model is rendered in front of the plane, however little (a plate thinner than the noise differs from
    the table by less than DISCRIMINATIVE_SIGMAS everywhere); and how many pixels those are."""
    window = _window_costs(view, centre, radius, lambda rays: np.vstack(
        [renderer.depth(T_cloud_model[None], rays), np.full((1, len(rays)), np.inf)]))
    if window is None:
        return np.zeros(2), 0
    cost, rendered, sigma = window
    telling = rendered[0] < rendered[1]
    return cost[:, telling].sum(axis=1), int(telling.sum())


def _window_costs(view: SceneView, centre: np.ndarray, radius: float, render, sweep: float = 0.0,
                  within: np.ndarray | None = None):
    """Over the measured pixels around the sphere (``centre``, ``radius``): each render's (K, P) cost in squared
    sigmas of the sensor's depth noise, at most RESIDUAL_CAP (a render that misses where the sensor measured costs
    the cap); the (K, P) depths ``render(rays)`` gives for the pixels' rays (P, 3), with the view's supporting
    plane behind them; and the (P,) sigmas. The cost is -2 log of the measurement's likelihood over the
    neighbours the sensor's lateral jitter may have read the pixel from (:mod:`psorr.verification.lateral_jitter`),
    but in a coarse search (``sweep`` > 0), whose poses lie a sweep apart: there the squared residual tells
    which is nearest as well, at a ninth of the work, and the fine step after it mixes.
    None when no pixel around it was measured."""
    pixels, U, V = _window_pixels(view, centre, radius, sweep, within)
    if len(pixels) == 0:
        return None
    observed = view.depth[pixels]
    noise = depth_noise()
    sigma = noise.depth_sigma(observed)
    offsets, weights = jitter_offsets(noise) if sweep == 0 else own_pixel()
    u = np.clip(U[:, None] + offsets[None, :, 0], 0, view.width - 1)
    v = np.clip(V[:, None] + offsets[None, :, 1], 0, view.height - 1)
    needed, where = np.unique(v * view.width + u, return_inverse=True)
    rays = view.rays(needed % view.width, needed // view.width)
    rendered = _behind_support(view, render(rays), rays)[:, where.reshape(u.shape)]  # (K, P, J)
    return mixture_costs(rendered, observed, sigma, weights, RESIDUAL_CAP), rendered[:, :, 0], sigma


def _behind_support(view: SceneView, rendered: np.ndarray, rays: np.ndarray) -> np.ndarray:
    """(K, P) the depths ``rendered`` along ``rays`` (P, 3), with the view's supporting plane behind them."""
    if view.support_plane is None:
        return rendered
    normal, offset = view.support_plane[:3], view.support_plane[3]
    towards = rays @ normal
    with np.errstate(divide="ignore"):
        plane = np.where(towards < 0, -offset / np.where(towards < 0, towards, -1.0), np.inf)
    return np.minimum(rendered, plane[None])


def differs(rendered: np.ndarray, other: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """(K, P) where depths ``rendered`` (K, P) and ``other`` (K or 1, P) differ: by more than
    DISCRIMINATIVE_SIGMAS x ``sigma`` (P,), or one hits the model and the other does not."""
    with np.errstate(invalid="ignore"):
        differs = np.abs(rendered - other) > DISCRIMINATIVE_SIGMAS * sigma[None]
    return differs | (np.isfinite(rendered) != np.isfinite(other))
