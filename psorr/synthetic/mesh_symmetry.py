"""A mesh's symmetries found from the mesh itself, for grading poses of parts that have no catalog entry.

A user's CAD part comes without the list of turns that map it onto itself, yet a pose that differs from
the truth by such a turn is the same pose to any sensor. :func:`find_symmetries` finds them:

- Every rotation symmetry of a rigid surface fixes its area centroid, so the candidates are turns about
  axes through it: the principal axes of the surface, and the normals of its largest planar facets
  (which a square or round section leaves undetermined among the principal axes).
- About each candidate axis, turns by 360/n degrees for n = 2 .. ``max_order`` are tried. A turn is
  kept when no surface sample moves further than ``tolerance`` x the mesh's diameter from the surface
  (the exact point-to-mesh distance, so tessellation adds almost nothing). The kept turns are closed
  into their group.
- An axis about which turns by several unrelated angles all pass is a continuous axis: the part is a
  surface of revolution about it, and turns about it are left to the continuous axis.

:func:`mesh_symmetric_add` is :func:`psorr.synthetic.catalog.symmetric_add` with these symmetries.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
import trimesh

from psorr.errors import InvalidInputError
from psorr.geometry import surface_moments
from psorr.geometry.rotations import turn_about_line
from psorr.synthetic.catalog import CONTINUOUS_STEP_DEG, model_diameter, symmetric_add


@dataclass(frozen=True)
class SymmetryParams:
    """Settings of :func:`find_symmetries`.

    Attributes:
        samples: surface samples moved by each candidate turn.
        tolerance: a turn is a symmetry when no moved sample lies further than this x the diameter
            from the surface.
        max_order: the largest n of the 360/n-degree turns tried about each axis.
        facet_axes: how many of the largest planar facets give their normal as a candidate axis.
        continuous_test_deg: turns that must all be symmetries for a continuous axis (no two of them
            are multiples of a common angle that a discrete symmetry of order <= 60 would have).
        seed: of the surface samples.
    """

    samples: int = 2000
    tolerance: float = 0.01
    max_order: int = 8
    facet_axes: int = 12
    continuous_test_deg: tuple[float, ...] = (13.0, 47.0, 98.0, 151.0)
    seed: int = 0

    def __post_init__(self):
        if self.samples < 10 or self.max_order < 2 or self.facet_axes < 0 or not 0 < self.tolerance < 1:
            raise InvalidInputError(f"SymmetryParams: need samples >= 10, max_order >= 2, facet_axes >= 0 and "
                                    f"0 < tolerance < 1, got {self}")


@dataclass(frozen=True, eq=False)
class MeshSymmetry:
    """The symmetries of a mesh, in its model frame (the mesh's own coordinates).

    Attributes:
        turns: (K, 4, 4) rigid transforms S with S(mesh) = mesh; the first is the identity. With a
            continuous axis, one turn per family of turns that differ by a spin about it.
        axis: (3,) unit direction of the continuous axis, or None.
        axis_point: (3,) a point on every symmetry axis (the surface's area centroid), model units.
        spherical: a second continuous axis holds too: every turn about ``axis_point`` maps the mesh onto itself.
    """

    turns: np.ndarray
    axis: np.ndarray | None
    axis_point: np.ndarray
    spherical: bool = False

    @property
    def symmetries(self) -> np.ndarray:
        """(M, 4, 4) every transform to search when grading: the turns, each composed with spins about the
        continuous axis every CONTINUOUS_STEP_DEG degrees when there is one."""
        if self.axis is None:
            return self.turns
        spins = np.array([turn_about_line(self.axis, np.radians(a), self.axis_point)
                          for a in np.arange(0.0, 360.0, CONTINUOUS_STEP_DEG)])
        return np.einsum("kij,mjl->kmil", self.turns, spins).reshape(-1, 4, 4)

    @property
    def continuous_axis(self) -> None:
        """Always None: the spins about a continuous axis are already among ``symmetries``, so that
        :func:`~psorr.synthetic.catalog.symmetric_add` takes a MeshSymmetry as it takes a catalog entry."""
        return None


class _SurfaceDistance:
    """Exact distance from points to one mesh's surface (Open3D's raycasting scene)."""

    def __init__(self, mesh: trimesh.Trimesh):
        self._scene = o3d.t.geometry.RaycastingScene()
        self._scene.add_triangles(o3d.core.Tensor(np.asarray(mesh.vertices, np.float32)),
                                  o3d.core.Tensor(np.asarray(mesh.faces, np.uint32)))

    def largest(self, points: np.ndarray, S: np.ndarray) -> float:
        moved = points @ S[:3, :3].T + S[:3, 3]
        return float(self._scene.compute_distance(o3d.core.Tensor(moved.astype(np.float32))).numpy().max())


def area_centroid(mesh: trimesh.Trimesh) -> np.ndarray:
    """(3,) the centroid of the mesh's surface, weighted by triangle area (fixed by every symmetry)."""
    return surface_moments.area_centroid(mesh.vertices, mesh.faces)


def principal_axes(mesh: trimesh.Trimesh) -> np.ndarray:
    """(3, 3) columns: the principal axes of the mesh's surface (its area's second moments about the area
    centroid, exact per triangle, so an exact symmetry axis comes out exact), smallest moment first."""
    return np.linalg.eigh(surface_moments.second_moments(mesh.vertices, mesh.faces))[1]


def candidate_axes(mesh: trimesh.Trimesh, facet_axes: int) -> list[np.ndarray]:
    """Unit directions (3,): the principal axes of the surface, then the normals of the ``facet_axes``
    largest planar facets, each direction once (up to sign)."""
    principal = principal_axes(mesh)
    facets = np.argsort(-mesh.facets_area)[:facet_axes] if len(mesh.facets) else []
    axes: list[np.ndarray] = []
    for axis in [*principal.T, *(mesh.facets_normal[k] for k in facets)]:
        axis = axis / np.linalg.norm(axis)
        if all(abs(axis @ a) < np.cos(np.radians(1.0)) for a in axes):
            axes.append(axis)
    return axes


def _closed_group(turns: list[np.ndarray], points: np.ndarray, tolerance: float, holds) -> list[np.ndarray]:
    """The turns (4, 4) closed under composition, identity first. Two turns are one when they carry the
    corners of ``points``' (N, 3) bounding box within ``tolerance`` (their unit) of each other, and so every
    point: a gear's exact turns and its near ones (a flip found about an axis 0.3 degrees off) are then one
    turn of 80, not drifting spins that fill the group's 200. A product joins only if ``holds(S)``: turns kept
    within the tolerance compose into turns that may not be (a flip 1.8 degrees off an exact one passes on
    a smooth part; their products spin it by 3.6, 7.2, ...)."""
    low, high = points.min(axis=0), points.max(axis=0)
    corners = np.array([[(low, high)[(k >> i) & 1][i] for i in range(3)] for k in range(8)])
    group, carried = [np.eye(4)], [corners]

    def known(S):
        moved = corners @ S[:3, :3].T + S[:3, 3]
        return bool((np.linalg.norm(np.asarray(carried) - moved, axis=2).max(axis=1) < tolerance).any())

    frontier = [S for S in turns if not known(S)]
    while frontier and len(group) < 200:
        S = frontier.pop()
        if known(S) or not holds(S):
            continue
        group.append(S)
        carried.append(corners @ S[:3, :3].T + S[:3, 3])
        frontier += [S @ G for G in group] + [G @ S for G in group]
    return group


def _flips(axis: np.ndarray, turns: list[np.ndarray]) -> list[np.ndarray]:
    """Of ``turns``, the first that turns the continuous ``axis`` end for end (all such differ by a spin)."""
    return [S for S in turns if S[:3, :3] @ axis @ axis < 0][:1]


def find_symmetries(mesh: trimesh.Trimesh, params: SymmetryParams | None = None) -> MeshSymmetry:
    """The turns that map ``mesh`` onto itself, and its continuous axis if it is a surface of revolution.

    Args:
        mesh: a triangle mesh in any length unit; the result is in its frame and unit.
        params: the search's settings; None for the defaults.
    """
    p = params or SymmetryParams()
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0 or not mesh.area > 0:
        raise InvalidInputError("find_symmetries() needs a trimesh.Trimesh with faces of non-zero area")
    points = np.asarray(trimesh.sample.sample_surface(mesh, p.samples, seed=p.seed)[0], np.float64)
    centre, limit = area_centroid(mesh), p.tolerance * model_diameter(mesh)
    surface = _SurfaceDistance(mesh)
    turns, continuous, spherical = [], None, False

    def revolves(axis: np.ndarray) -> bool:
        return all(surface.largest(points, turn_about_line(axis, np.radians(a), centre)) <= limit
                   for a in p.continuous_test_deg)

    for axis in candidate_axes(mesh, p.facet_axes):
        if continuous is None and revolves(axis):
            continuous = axis
            continue
        if continuous is not None and not spherical and abs(axis @ continuous) < 0.5 and revolves(axis):
            spherical = True  # a second axis of revolution, across the first: a ball, which every turn keeps
            continue
        turns += [S for n in range(2, p.max_order + 1) if surface.largest(points, S := turn_about_line(
            axis, 2 * np.pi / n, centre)) <= limit]
    if continuous is not None:
        # Every other turn of a surface of revolution turns its axis end for end, and all such differ by a
        # spin about it: one flip found is all of them, with no group to close.
        return MeshSymmetry(np.array([np.eye(4), *_flips(continuous, turns)]), continuous, centre, spherical)
    group = _closed_group(turns, points, limit, lambda S: surface.largest(points, S) <= limit)
    return MeshSymmetry(np.array(group), None, centre)


def mesh_symmetric_add(points_model, T_est, T_true, symmetry: MeshSymmetry) -> float:
    """Symmetry-aware ADD (in the points' unit) of an estimated against a true pose (4, 4, model -> camera),
    over ``symmetry``'s transforms: :func:`psorr.synthetic.catalog.symmetric_add` for a mesh of one's own."""
    if not isinstance(symmetry, MeshSymmetry):
        raise InvalidInputError(f"symmetry must be a MeshSymmetry (from find_symmetries(mesh)), got a "
                                f"{type(symmetry).__name__}")
    if symmetry.spherical:  # some turn about its centre lines the two poses up: only the centres can differ
        centre = np.append(symmetry.axis_point, 1.0)
        return float(np.linalg.norm((np.asarray(T_est) @ centre - np.asarray(T_true) @ centre)[:3]))
    return symmetric_add(points_model, T_est, T_true, symmetry)


def match_detections(instances, detections, known, share: float = 0.1) -> tuple[list[bool], list[bool]]:
    """(found per instance, correct per detection): each detection, in order, finds the first instance
    (``T_camera_model`` and ``name``) of its model not yet found within a symmetry-aware ADD of ``share`` x
    the model's diameter; any other detection is false, a second report of an instance included.
    ``known(name)`` gives a model's (surface samples (N, 3), MeshSymmetry, diameter), or None for a model
    that no instance can be."""
    found, correct = [False] * len(instances), []
    for det in detections:
        model = known(det.model)
        hit = None if model is None else next(
            (k for k, inst in enumerate(instances) if not found[k] and inst.name == det.model
             and mesh_symmetric_add(model[0], det.T_cloud_model, inst.T_camera_model, model[1]) < share * model[2]),
            None)
        correct.append(hit is not None)
        if hit is not None:
            found[hit] = True
    return found, correct
