"""A closed mesh with fewer faces for CoACD's search, no further from the part than a share of the hulls' own slack.

CoACD's time grows with the faces each cut clips and samples, and a CAD export spends thousands of faces on
fillets and chamfers far finer than the 5 mm its hulls may stand off the surface (decision record 0055). So
the search runs on the part decimated (Open3D's quadric decimation) as far as it stays closed, within
``tolerance`` of the part both ways, and facing the way the part faces: quadric decimation does not guard
against folding a triangle over, and a decimation with folds (5% of a printed part's surface at 1 mm) made
CoACD crash on one cut and hang on another. The hulls are then still clamped to the part's own box. Decision
record 0063 has the measurements.
"""

from __future__ import annotations

import numpy as np
import open3d as o3d
import trimesh

_SAMPLES = 20000  # surface samples each way for the deviation; seeded, so a mesh always gets the same answer
_MIN_FACES = 200  # no coarser: a box needs 12, and below a few hundred a search costs nothing anyway
# Share of the decimated surface that may face against the part's nearest face. Samples beside a sharp edge
# find the face across it, so sound decimations of 4 printed parts showed 0.0003-0.0006; a folded one 0.05.
_MAX_FOLDED = 0.005
_STEP = 0.7  # each try keeps this share of the faces of the last one that passed


def simplified(mesh: trimesh.Trimesh, tolerance: float) -> trimesh.Trimesh | None:
    """``mesh`` (closed, metres) decimated, in steps of 0.7 of the faces, as far as the result stays closed, every
    sample of either surface lies within ``tolerance`` metres of the other and it does not fold over; None when
    no step does."""
    if not mesh.is_watertight or len(mesh.faces) < 2 * _MIN_FACES:
        return None
    source = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(mesh.vertices),
                                       o3d.utility.Vector3iVector(mesh.faces))
    samples = _samples(mesh)
    surface = _distance_scene(mesh)
    best, target = None, int(len(mesh.faces) * _STEP)
    while target >= _MIN_FACES:
        decimated = source.simplify_quadric_decimation(target)
        candidate = trimesh.Trimesh(np.asarray(decimated.vertices), np.asarray(decimated.triangles), process=False)
        candidate.merge_vertices(digits_vertex=12)
        if not candidate.is_watertight or _deviation(candidate, samples, surface) > tolerance \
                or _folded_share(candidate, mesh, surface) > _MAX_FOLDED:
            break
        best, target = candidate, int(target * _STEP)
    return best


def _samples(mesh: trimesh.Trimesh, faces: bool = False):
    points, face = trimesh.sample.sample_surface(mesh, _SAMPLES, seed=0)
    points = np.asarray(points, dtype=np.float32)
    return (points, face) if faces else points


def _distance_scene(mesh: trimesh.Trimesh) -> o3d.t.geometry.RaycastingScene:
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(mesh.vertices, dtype=np.float32)),
                        o3d.core.Tensor(np.asarray(mesh.faces, dtype=np.uint32)))
    return scene


def _deviation(candidate: trimesh.Trimesh, part_samples: np.ndarray,
               part_surface: o3d.t.geometry.RaycastingScene) -> float:
    """The largest distance (m) from a sample of either surface to the other."""
    to_candidate = _distance_scene(candidate).compute_distance(o3d.core.Tensor(part_samples)).numpy()
    to_part = part_surface.compute_distance(o3d.core.Tensor(_samples(candidate))).numpy()
    return float(max(to_candidate.max(), to_part.max()))


def _folded_share(candidate: trimesh.Trimesh, part: trimesh.Trimesh,
                  part_surface: o3d.t.geometry.RaycastingScene) -> float:
    """The share of ``candidate``'s surface (by area, sampled) whose normal points against the normal of the
    part's face nearest to it."""
    points, faces = _samples(candidate, faces=True)
    nearest = part_surface.compute_closest_points(o3d.core.Tensor(points))["primitive_ids"].numpy()
    facing = np.einsum("ij,ij->i", candidate.face_normals[faces], part.face_normals[nearest])
    return float(np.mean(facing < 0))
