"""Analytic plane and cylinder geometry: distances, expected normals, fits.

Parameters follow `Primitive.params`: a plane is (nx, ny, nz, d) with
n.x + d = 0; a cylinder is (px, py, pz, ax, ay, az, r). Everything is
vectorised over points, metres throughout.
"""

from __future__ import annotations

import numpy as np

from psorr.geometry.boxes import orthonormal_frame
from psorr.geometry.columns import column_mean
from psorr.types import PrimitiveKind

_EPS = 1e-12


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), _EPS)


def distances(kind: PrimitiveKind, params, points: np.ndarray) -> np.ndarray:
    """(N,) absolute distance of each point to the shape's surface."""
    p = np.asarray(params, float)
    if kind is PrimitiveKind.PLANE:
        return np.abs(points @ p[:3] + p[3])
    rel = points - p[:3]
    along = rel @ p[3:6]
    radial = np.sqrt(np.maximum(np.einsum("ij,ij->i", rel, rel) - along**2, 0.0))
    return np.abs(radial - p[6])


def surface_normals(kind: PrimitiveKind, params, points: np.ndarray) -> np.ndarray:
    """(N, 3) the shape's unit normal at the foot of each point (sign not meaningful)."""
    p = np.asarray(params, float)
    if kind is PrimitiveKind.PLANE:
        return np.broadcast_to(p[:3], points.shape)
    rel = points - p[:3]
    radial = rel - np.outer(rel @ p[3:6], p[3:6])
    return _unit(radial)


def normal_agreement(kind: PrimitiveKind, params, points, normals) -> np.ndarray:
    """(N,) cos of the angle between the measured and the shape's normals.

    Signed for planes, whose normal faces the same way as the points' (towards
    the sensor, or outwards on a CAD part): the two sides of a 1.5 mm sheet
    must not explain each other. A cylinder's |cos| serves outer walls and bores.
    """
    if kind is PrimitiveKind.PLANE:
        return normals @ np.asarray(params[:3], float)
    return np.abs(np.einsum("ij,ij->i", surface_normals(kind, params, points), normals))


def faces_outward(params, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(N,) bool: does each oriented point's normal face away from the cylinder's axis?

    True on an outer wall, False in a bore (normals face the sensor, or outwards
    on a CAD part, so a bore's visible wall faces its axis). normal_agreement
    ignores this sign, so a bush's wall and its bore, one coaxial radius apart,
    can fall to one cylinder of the radius in between.
    """
    radial = surface_normals(PrimitiveKind.CYLINDER, params, points)
    return np.einsum("ij,ij->i", radial, normals) > 0


def support_counts(kind: PrimitiveKind, params: np.ndarray, points, normals, threshold, cos_max):
    """(C,) how many of the (N, 3) oriented points each of C shapes of one
    kind explains: within `threshold` ((N,) metres) and normals within the angle."""
    params = np.asarray(params, float)
    if kind is PrimitiveKind.PLANE:
        dist = np.abs(points @ params[:, :3].T + params[:, 3])
        agree = normals @ params[:, :3].T
        return ((dist < threshold[:, None]) & (agree > cos_max)).sum(axis=0)
    rel = points[None, :, :] - params[:, None, :3]
    along = np.einsum("cnj,cj->cn", rel, params[:, 3:6])
    radial = rel - along[:, :, None] * params[:, None, 3:6]
    r = np.linalg.norm(radial, axis=2)
    agree = np.abs(np.einsum("cnj,nj->cn", radial, normals)) / np.maximum(r, _EPS)
    return ((np.abs(r - params[:, 6:7]) < threshold) & (agree > cos_max)).sum(axis=1)


def fit_plane(points: np.ndarray, normals: np.ndarray | None = None) -> tuple[float, ...]:
    """Least-squares plane through (N, 3) points. Its normal faces the way the
    points' (N, 3) normals do on average, or, without normals, the sensor at
    the origin (so that d > 0 for a plane in front of it)."""
    centroid = column_mean(points)
    centred = points - centroid
    _, vecs = np.linalg.eigh(centred.T @ centred)
    normal = vecs[:, 0]
    facing = -(normal @ centroid) if normals is None else normal @ column_mean(normals)
    if facing < 0:
        normal = -normal
    return (*normal, float(-normal @ centroid))


def _circle_about(points: np.ndarray, axis: np.ndarray):
    """Algebraic (Kasa) circle of the points projected along `axis`:
    (centre (3,), radius, rms residual) or None."""
    u, v = orthonormal_frame(axis)
    centroid = column_mean(points)
    rel = points - centroid
    x, y = rel @ u, rel @ v
    # x^2 + y^2 = 2ax + 2by + c is linear in (a, b, c); the 3x3 normal
    # equations are plenty accurate for centred points and much faster than lstsq.
    design = np.column_stack([2 * x, 2 * y, np.ones_like(x)])
    try:
        a, b, c = np.linalg.solve(design.T @ design, design.T @ (x**2 + y**2))
    except np.linalg.LinAlgError:
        return None
    r2 = c + a * a + b * b
    if not np.isfinite(r2) or r2 <= 0:
        return None
    radius = np.sqrt(r2)
    rms = np.sqrt(np.mean((np.hypot(x - a, y - b) - radius) ** 2))
    # The axis point sits level with the centroid, mid-span.
    return centroid + a * u + b * v, float(radius), float(rms)


def fit_cylinder(points: np.ndarray, normals: np.ndarray) -> tuple[float, ...] | None:
    """Cylinder through (N, 3) points with (N, 3) normals, or None if degenerate.

    Normals are perpendicular to the axis, so the axis is the direction their
    scatter is smallest along. On a short arc the two smallest directions are
    nearly tied and noise decides between them, so a circle is fitted about
    both and the one the points fit better wins.
    """
    if len(points) < 6:
        return None
    _, vecs = np.linalg.eigh(normals.T @ normals)
    best = None
    for axis in (vecs[:, 0], vecs[:, 1]):
        circle = _circle_about(points, axis)
        if circle is not None and (best is None or circle[2] < best[1][2]):
            best = (axis, circle)
    if best is None:
        return None
    axis, (centre, radius, _) = best
    return (*centre, *axis, radius)


def refine_cylinder(points: np.ndarray, params, max_points: int = 3000, rng=None) -> tuple[float, ...]:
    """Geometric least-squares cylinder (point-to-surface distances) from a
    starting guess. The normals-based axis and algebraic circle of
    fit_cylinder are biased on a short, noisy arc; this removes the bias.
    Uses an evenly strided subset of at most `max_points` points."""
    from scipy.optimize import least_squares

    p0 = np.asarray(params, float)
    stride = max(1, len(points) // max_points)
    problem = _CylinderFit(points[::stride], p0)
    result = least_squares(problem.residuals, np.array([0.0, 0.0, 0.0, 0.0, p0[6]]), jac=problem.jacobian,
                           method="lm", max_nfev=200)
    centre, axis, radius = problem.unpack(result.x)
    if not np.isfinite(result.x).all() or radius <= 0:
        return tuple(float(x) for x in p0)
    # Keep the axis point level with the points' centroid, as fit_cylinder does.
    centre = centre + ((column_mean(points) - centre) @ axis) * axis
    return (*centre, *axis, float(abs(radius)))


class _CylinderFit:
    """The geometric cylinder fit of (N, 3) ``points`` about a start ``p0`` (7,), in five unknowns x: the
    axis tilted by x0 u + x1 v, the axis point moved by x2 u + x3 v (u, v across the start axis), and the
    radius x4."""

    def __init__(self, points: np.ndarray, p0: np.ndarray):
        self.points, self.p0 = points, p0
        self.axis0 = p0[3:6] / np.linalg.norm(p0[3:6])
        self.u, self.v = orthonormal_frame(self.axis0)

    def unpack(self, x):
        axis = _unit(self.axis0 + x[0] * self.u + x[1] * self.v)
        return self.p0[:3] + x[2] * self.u + x[3] * self.v, axis, x[4]

    def residuals(self, x) -> np.ndarray:
        """(N,) each point's distance to the axis less the radius."""
        centre, axis, radius = self.unpack(x)
        rel = self.points - centre
        along = rel @ axis
        return np.sqrt(np.maximum(np.einsum("ij,ij->i", rel, rel) - along**2, 0.0)) - radius

    def jacobian(self, x) -> np.ndarray:
        """(N, 5) d residuals / dx, analytic: finite differences cost five more residual passes each step.
        With d = rel - (rel.a) a, a point's offset from the axis, moving the axis point by c changes r by
        -d.c / |d|, and tilting the axis (a = w / |w|) by -(rel.a) d.dw / (|d| |w|)."""
        centre, axis, _ = self.unpack(x)
        rel = self.points - centre
        along = rel @ axis
        d = rel - along[:, None] * axis
        dist = np.maximum(np.linalg.norm(d, axis=1), 1e-12)
        du, dv = d @ self.u / dist, d @ self.v / dist
        tilt = -along / np.linalg.norm(self.axis0 + x[0] * self.u + x[1] * self.v)
        return np.column_stack([tilt * du, tilt * dv, -du, -dv, -np.ones(len(rel))])


def fit(kind: PrimitiveKind, points: np.ndarray, normals: np.ndarray, refine: bool = False,
        max_radius: float = np.inf):
    """Fit a shape of `kind`; `refine` adds the geometric refinement for cylinders.
    Returns params, or None if the points do not determine one (a cylinder
    wider than `max_radius` is a plane in disguise and counts as none)."""
    if kind is PrimitiveKind.PLANE:
        return fit_plane(points, normals) if len(points) >= 3 else None
    params = fit_cylinder(points, normals)
    if params is not None and refine:
        params = refine_cylinder(points, params)
    if params is None or params[6] > max_radius:
        return None
    return params


def cylinders_from_point_pairs(p1, n1, p2, n2, min_sin: float = 0.05):
    """Cylinders from pairs of oriented points, vectorised over M pairs.

    The axis runs along n1 x n2 through the midpoint of the shortest segment
    between the two normal lines; the radius is p1's distance to that axis.
    Returns (params (K, 7), kept (K,) indices of the pairs that gave one):
    pairs with near-parallel normals say nothing about an axis and are dropped.
    """
    axis = np.cross(n1, n2)
    sin = np.linalg.norm(axis, axis=1)
    kept = np.flatnonzero(sin > min_sin)
    if kept.size == 0:
        return np.empty((0, 7)), kept
    p1, n1, p2, n2, axis = p1[kept], n1[kept], p2[kept], n2[kept], axis[kept] / sin[kept, None]
    # Closest points p1 + t n1 and p2 + s n2 on the two normal lines.
    w = p1 - p2
    b = np.einsum("ij,ij->i", n1, n2)
    d = np.einsum("ij,ij->i", n1, w)
    e = np.einsum("ij,ij->i", n2, w)
    denom = 1.0 - b * b
    t = (b * e - d) / denom
    s = (e - b * d) / denom
    center = 0.5 * ((p1 + t[:, None] * n1) + (p2 + s[:, None] * n2))
    rel = p1 - center
    along = np.einsum("ij,ij->i", rel, axis)
    radius = np.linalg.norm(rel - along[:, None] * axis, axis=1)
    return np.column_stack([center, axis, radius]), kept
