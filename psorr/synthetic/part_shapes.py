"""What kind of part a mesh is, from the mesh alone: thin, flanged, turned, freeform or prismatic.

Users bring their own parts, so a benchmark that reports by kind of part must tell the kind from the
mesh (in metres). The measures:

- **resting height**: the part's height as it rests in its most probable stable pose
  (:func:`~psorr.synthetic.resting.stable_rests`);
- **large primitives**: the share of the surface area on large planes and cylinders, each at least
  (``min_region`` x diameter)^2: planar regions (trimesh's facets of coplanar neighbouring triangles,
  and lone triangles), and smooth patches of the other triangles (neighbours bent by under
  ``smooth_deg``) whose normals all point at one axis from one radius (within ``cylinder_tolerance``).
  A freeform surface has few, and so has a part broken into many small features (ribs, slots,
  bosses): either way, the large primitives a recognizer matches are few;
- **revolution**: the share of surface samples that a surface of revolution about the best candidate
  axis (the principal axes through the area centroid, the large cylinders' axes) could hold: a normal
  with no component along the turning direction (within ``revolution_tolerance``); its **side** share
  counts those whose normal faces more across the axis than along it (a cylinder's or cone's, not a
  disc's, so that a flat plate, all discs about its normal, does not count as turned).

The class is the first that applies:

- **thin**: at most ``thin_height`` (8 mm) high as it rests;
- **flanged**: turned, with a disc wider than its body: of ``slices`` slices along the axis, those
  wider than ``flange_ratio`` x the median slice make up at most ``flange_length`` of the length;
- **turned**: a continuous symmetry axis (:func:`~psorr.synthetic.mesh_symmetry.find_symmetries`), or
  a revolution share of at least ``turned_share`` with a side share of at least ``turned_side_share``;
- **freeform**: under ``freeform_share`` of the area on large primitives;
- **prismatic**: the rest (mostly large planes, and cylinders that share no axis).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from psorr.errors import InvalidInputError
from psorr.synthetic.catalog import model_diameter
from psorr.synthetic.mesh_symmetry import MeshSymmetry, area_centroid, find_symmetries, principal_axes
from psorr.synthetic.resting import stable_rests


class PartClass(StrEnum):
    THIN = "thin"
    FLANGED = "flanged"
    TURNED = "turned"
    FREEFORM = "freeform"
    PRISMATIC = "prismatic"


@dataclass(frozen=True)
class ShapeParams:
    """Settings of :func:`part_shape` (see the module docstring); lengths in metres.

    ``samples``: surface samples for the revolution share (seeded, so a mesh always gets one class).
    """

    thin_height: float = 0.008
    min_region: float = 0.15
    smooth_deg: float = 35.0
    cylinder_tolerance: float = 0.1
    revolution_tolerance: float = 0.26
    turned_share: float = 0.8
    turned_side_share: float = 0.25
    freeform_share: float = 0.5
    flange_ratio: float = 1.25
    flange_length: float = 0.4
    slices: int = 20
    samples: int = 4000


@dataclass(frozen=True)
class PartShape:
    """The measures of one part and its class. Lengths in metres, shares of the surface area.

    Attributes:
        part_class: the first class that applies (module docstring).
        resting_height: height as it rests in its most probable stable pose.
        primitive_share: area on large planes and cylinders.
        revolution_share: area that a surface of revolution about the best candidate axis could hold
            (1 with a continuous symmetry axis); side_share: of that, the area facing across the axis.
        continuous_axis: whether the part is a surface of revolution.
        flanged: whether, turned, it has a disc wider than its body.
    """

    part_class: PartClass
    resting_height: float
    primitive_share: float
    revolution_share: float
    side_share: float
    continuous_axis: bool
    flanged: bool


def _planar_faces(mesh: trimesh.Trimesh, min_area: float) -> np.ndarray:
    """(F,) bool: faces in a planar region (a facet or a lone face) of at least ``min_area``."""
    planar = mesh.area_faces >= min_area
    for facet, area in zip(mesh.facets, mesh.facets_area):
        planar[facet] = area >= min_area
    return planar


def _smooth_patches(mesh: trimesh.Trimesh, keep: np.ndarray, smooth_deg: float) -> list[np.ndarray]:
    """Face index arrays of the connected patches of the ``keep`` faces whose neighbours bend by under
    ``smooth_deg`` degrees."""
    pairs = mesh.face_adjacency[(mesh.face_adjacency_angles < np.radians(smooth_deg))
                                & keep[mesh.face_adjacency].all(axis=1)]
    n = len(mesh.faces)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    order = np.argsort(labels, kind="stable")
    groups = np.split(order, np.flatnonzero(np.diff(labels[order])) + 1)
    return [g for g in groups if keep[g[0]]]


def _cylinder_axis(centres: np.ndarray, normals: np.ndarray, weights: np.ndarray,
                   tolerance: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(point, unit direction) of the axis that the faces' normals all point at from one radius, or None."""
    _, vectors = np.linalg.eigh(np.einsum("f,fi,fj->ij", weights, normals, normals))
    axis = vectors[:, 0]
    if np.average(np.abs(normals @ axis), weights=weights) > tolerance:
        return None
    basis = np.linalg.svd(np.eye(3) - np.outer(axis, axis))[0][:, :2]
    p, n = centres @ basis, normals @ basis
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    across = np.eye(2)[None] - np.einsum("fi,fj->fij", n, n)  # distance to each normal line
    centre = np.linalg.lstsq(np.einsum("f,fij->ij", weights, across),
                             np.einsum("f,fij,fj->i", weights, across, p), rcond=None)[0]
    radius = np.linalg.norm(p - centre, axis=1)
    mean = np.average(radius, weights=weights)
    if not mean > 0 or np.sqrt(np.average((radius - mean) ** 2, weights=weights)) > tolerance * mean:
        return None
    return basis @ centre, axis


def _cylinders(mesh: trimesh.Trimesh, planar: np.ndarray, p: ShapeParams, min_area: float) -> list[tuple]:
    """(area, point, direction) of each cylindrical patch of at least ``min_area`` off the planar faces."""
    found = []
    for patch in _smooth_patches(mesh, ~planar, p.smooth_deg):
        area = float(mesh.area_faces[patch].sum())
        if area < min_area:
            continue
        axis = _cylinder_axis(mesh.triangles_center[patch], mesh.face_normals[patch], mesh.area_faces[patch],
                              p.cylinder_tolerance)
        if axis is not None:
            found.append((area, *axis))
    return found


def _revolution_share(points: np.ndarray, normals: np.ndarray, point: np.ndarray, axis: np.ndarray,
                      tolerance: float) -> tuple[float, float]:
    """Shares of the samples (N, 3) with normals (N, 3) that a surface of revolution about the axis (point,
    unit direction) could hold: all such (a normal without a component along the turning direction), and
    those among them whose normal is more across the axis than along it (a cylinder's or a cone's, not
    a disc's)."""
    offset = points - point
    radial = offset - np.outer(offset @ axis, axis)
    length = np.linalg.norm(radial, axis=1)
    turning = np.cross(axis, radial / np.maximum(length, 1e-12)[:, None])
    fits = (np.abs(np.einsum("ij,ij->i", normals, turning)) < tolerance) | (length < 1e-9)
    return float(fits.mean()), float((fits & (np.abs(normals @ axis) < np.sqrt(0.5))).mean())


def _turning_axis(mesh: trimesh.Trimesh, points: np.ndarray, normals: np.ndarray, symmetry: MeshSymmetry,
                  cylinders: list[tuple], p: ShapeParams) -> tuple[float, float, tuple]:
    """(revolution share, its side share, (point, direction)) of the surface samples (N, 3) with normals
    (N, 3) about the continuous symmetry axis if there is one, else about the best of the candidate axes:
    the principal axes through the area centroid, and the axes of the cylinders."""
    if symmetry.axis is not None:
        candidates = [(symmetry.axis_point, symmetry.axis)]
    else:
        candidates = [(area_centroid(mesh), a) for a in principal_axes(mesh).T] + [(q, d) for _, q, d in cylinders]
    scored = [(*_revolution_share(points, normals, q, d, p.revolution_tolerance), (q, d)) for q, d in candidates]
    return max(scored, key=lambda s: s[0])


def _flanged(points: np.ndarray, point: np.ndarray, axis: np.ndarray, p: ShapeParams) -> bool:
    """Do the slices along the axis wider than flange_ratio x the median slice make up at most flange_length?
    Slices of the surface samples (N, 3); a slice no sample falls in is left out."""
    along = (points - point) @ axis
    radius = np.linalg.norm(np.cross(points - point, axis), axis=1)
    edges = np.linspace(along.min(), along.max(), p.slices + 1)
    slot = np.clip(np.searchsorted(edges, along, side="right") - 1, 0, p.slices - 1)
    widest = np.full(p.slices, -1.0)
    np.maximum.at(widest, slot, radius)
    widest = widest[widest >= 0]
    wide = widest > p.flange_ratio * np.median(widest)
    return bool(wide.any() and wide.mean() <= p.flange_length)


def part_shape(mesh: trimesh.Trimesh, symmetry: MeshSymmetry | None = None,
               params: ShapeParams | None = None) -> PartShape:
    """Measure and classify one part.

    Args:
        mesh: the part, in metres.
        symmetry: its symmetries if already found (None: found here).
        params: the thresholds; None for the defaults.
    """
    p = params or ShapeParams()
    if not isinstance(mesh, trimesh.Trimesh) or not mesh.area > 0:
        raise InvalidInputError("part_shape() needs a trimesh.Trimesh with faces of non-zero area (in metres)")
    symmetry = symmetry or find_symmetries(mesh)
    diameter = model_diameter(mesh)
    min_area = (p.min_region * diameter) ** 2
    planar = _planar_faces(mesh, min_area)
    cylinders = _cylinders(mesh, planar, p, min_area)
    points, faces = trimesh.sample.sample_surface(mesh, p.samples, seed=0)
    revolution, side, axis = _turning_axis(mesh, points, mesh.face_normals[faces], symmetry, cylinders, p)
    turned = symmetry.axis is not None or (revolution >= p.turned_share and side >= p.turned_side_share)
    surface = (float(mesh.area_faces[planar].sum()) + sum(c[0] for c in cylinders)) / mesh.area
    flanged = turned and _flanged(points, *axis, p)
    height = stable_rests(mesh)[0].height
    if height <= p.thin_height + 1e-6:  # 1 um: an STL's float32 coordinates make 8 mm 8.000003 mm
        kind = PartClass.THIN
    elif turned:
        kind = PartClass.FLANGED if flanged else PartClass.TURNED
    else:
        kind = PartClass.FREEFORM if surface < p.freeform_share else PartClass.PRISMATIC
    return PartShape(kind, height, surface, revolution, side, symmetry.axis is not None, flanged)
