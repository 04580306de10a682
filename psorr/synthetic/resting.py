"""How a part rests on a table, and room for several on one table without overlap.

:func:`stable_rests` lists the poses a dropped part comes to rest in, with their probabilities
(``trimesh.poses.compute_stable_poses``, which needs networkx). Each rest's footprint is the convex
hull of the part's outline seen from above; :func:`place_footprints` lays footprints out in a patch
of the table with a clearance between every two (the separating-axis test of convex polygons).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError

from psorr.errors import InvalidInputError, PsorrError
from psorr.geometry.solids import centre_of_mass


@dataclass(frozen=True, eq=False)
class Rest:
    """One stable resting pose of a part.

    Attributes:
        T_table_model: (4, 4) model -> table frame: the part touches the plane z = 0 from above, and its
            footprint's centroid is at x = y = 0.
        probability: the chance that a dropped part comes to rest so (the rests of a part sum to 1).
        footprint: (K, 2) the convex outline seen from above, counter-clockwise, table frame.
        height: the part's height above the table as it rests, in the mesh's unit.
    """

    T_table_model: np.ndarray
    probability: float
    footprint: np.ndarray
    height: float


_RESTS: dict[str, tuple[Rest, ...]] = {}
# Decimals to which rests' probabilities (and up directions) are compared when ordering them: a symmetric
# part's copies of one rest differ by 1e-10 and less (rounding that differs between CPUs). Two distinct rests
# closer than this are ordered by direction too, which changes only which draw gives which.
PROBABILITY_DIGITS = 6
# A compute budget, not a shape constant: trimesh's stable poses take time superlinear in the hull's faces
# (a 1024-sided cylinder 3 s, a 5120-face ball 11 s; a 327,000-face ball, every facet a rest, hours). A hull
# of more faces than HULL_FACES is replaced by the hull of its extreme vertices in SUPPORT_DIRECTIONS spread
# directions, which lies within a few thousandths of the part's radius of it. The 45 Prusa parts' hulls have
# at most 772 faces, so their rests are trimesh's on their own hulls (docs/decisions/0075).
HULL_FACES = 1024
SUPPORT_DIRECTIONS = 512


def _mesh_key(mesh: trimesh.Trimesh) -> str:
    return hashlib.sha1(np.ascontiguousarray(mesh.vertices).tobytes() + np.ascontiguousarray(mesh.faces).tobytes()
                        ).hexdigest()


def _outline(points: np.ndarray) -> np.ndarray:
    """(K, 2) counter-clockwise convex hull of the (N, 2) points (a degenerate outline: its extreme points)."""
    try:
        return points[ConvexHull(points).vertices]
    except QhullError:
        return points[ConvexHull(points, qhull_options="QJ").vertices]


def _rest(T: np.ndarray, probability: float, mesh: trimesh.Trimesh) -> Rest:
    on_table = mesh.vertices @ T[:3, :3].T + T[:3, 3]
    outline = _outline(on_table[:, :2])
    centre = outline.mean(axis=0)
    T = T.copy()
    T[:2, 3] -= centre
    T[2, 3] -= on_table[:, 2].min()  # touching exactly
    return Rest(T, float(probability), outline - centre, float(np.ptp(on_table[:, 2])))


def stable_rests(mesh: trimesh.Trimesh) -> tuple[Rest, ...]:
    """The stable resting poses of ``mesh`` (any unit), most probable first; computed once per mesh.

    Raises:
        PsorrError: networkx, which trimesh's stable poses need, is not installed (pip install networkx).
    """
    key = _mesh_key(mesh)
    if key not in _RESTS:
        from psorr.library.derived import derived  # the disk cache: the next process reads them

        # The in-process key is already the hash of the vertices and faces: not hashed again from the arrays.
        _RESTS[key] = derived("rests", (key,), lambda: _found_rests(mesh), _encode, _decode)
    return _RESTS[key]


def _found_rests(mesh: trimesh.Trimesh) -> tuple[Rest, ...]:
    """The stable resting poses of ``mesh``, found (see :func:`stable_rests`)."""
    try:
        import networkx  # noqa: F401  (trimesh imports it softly and fails late without it)
    except ImportError as exc:
        raise PsorrError("resting poses need networkx (trimesh.poses.compute_stable_poses): "
                         "pip install networkx") from exc
    hull = _resting_hull(mesh)
    with np.errstate(invalid="ignore"):  # trimesh takes square roots of rounding-negative numbers
        transforms, probabilities = trimesh.poses.compute_stable_poses(hull, center_mass=centre_of_mass(mesh))
    if len(probabilities) == 0:
        raise InvalidInputError("trimesh found no stable resting pose for the mesh; is it a closed solid?")
    probabilities = np.asarray(probabilities) / np.sum(probabilities)
    order = _canonical_order(np.asarray(transforms), probabilities)
    # Outlines and heights from what the rests were found on: a simplified hull's few vertices, not 160,000.
    return tuple(_rest(transforms[k], probabilities[k], hull) for k in order)


def _encode(rests: tuple[Rest, ...]) -> dict:
    return {"T_table_model": np.array([r.T_table_model for r in rests]).reshape(-1, 4, 4),
            "probability": np.array([r.probability for r in rests], dtype=np.float64),
            "height": np.array([r.height for r in rests], dtype=np.float64),
            "footprint": np.concatenate([r.footprint for r in rests]).reshape(-1, 2),
            "footprint_sizes": np.array([len(r.footprint) for r in rests], dtype=np.int64)}


def _decode(arrays) -> tuple[Rest, ...]:
    footprints = np.split(arrays["footprint"], np.cumsum(arrays["footprint_sizes"])[:-1])
    return tuple(Rest(T, float(p), f, float(h)) for T, p, f, h in
                 zip(arrays["T_table_model"], arrays["probability"], footprints, arrays["height"]))


def _resting_hull(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """What the rests are found on: ``mesh`` itself (trimesh takes its convex hull) or, when that hull has more than
    HULL_FACES faces, the hull of its extreme vertices in SUPPORT_DIRECTIONS directions spread over the sphere."""
    hull = mesh.convex_hull
    if len(hull.faces) <= HULL_FACES:
        return mesh
    k = np.arange(SUPPORT_DIRECTIONS) + 0.5
    up = 1.0 - 2.0 * k / SUPPORT_DIRECTIONS
    turn = np.pi * (1.0 + np.sqrt(5.0)) * k  # the golden angle: an even spread (Fibonacci sphere)
    across = np.sqrt(1.0 - up**2)
    directions = np.column_stack([across * np.cos(turn), across * np.sin(turn), up])
    # Row by row over a block of directions: one (512, N) product of a 160,000-vertex hull is 650 MB.
    extremes = np.unique(np.concatenate([np.argmax(block @ hull.vertices.T, axis=1)
                                         for block in np.array_split(directions, 16)]))
    return trimesh.convex.convex_hull(hull.vertices[extremes])


def _canonical_order(transforms: np.ndarray, probabilities: np.ndarray) -> np.ndarray:
    """Indices of the rests, most probable first, rests whose probabilities agree to PROBABILITY_DIGITS
    decimals ordered by the direction (model frame) that points up in them. trimesh orders by probability
    alone, and the rests a symmetric part takes alike (a three-spoked knob on each spoke) differ there in
    the last bits, which need not be the same on another CPU: which rest a seed drew hung on them."""
    up = np.round(transforms[:, 2, :3], PROBABILITY_DIGITS)
    rounded = np.round(probabilities, PROBABILITY_DIGITS)
    return np.lexsort((up[:, 2], up[:, 1], up[:, 0], -rounded))


def draw_rest(rng: np.random.Generator, rests: tuple[Rest, ...]) -> Rest:
    """One of ``rests``, drawn by its probability."""
    return rests[int(rng.choice(len(rests), p=[r.probability for r in rests]))]


def _separated(a: np.ndarray, b: np.ndarray, gap: float) -> bool:
    """Are the convex polygons (K, 2) and (L, 2) at least ``gap`` apart along one of their edge normals?"""
    for polygon in (a, b):
        edges = np.roll(polygon, -1, axis=0) - polygon
        normals = np.column_stack((edges[:, 1], -edges[:, 0]))
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
        pa, pb = a @ normals.T, b @ normals.T
        if np.any(np.maximum(pb.min(axis=0) - pa.max(axis=0), pa.min(axis=0) - pb.max(axis=0)) >= gap):
            return True
    return False


def _posed(footprint: np.ndarray, x: float, y: float, yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return footprint @ np.array([[c, s], [-s, c]]) + (x, y)


def _try_layout(rng, footprints: list[np.ndarray], half_extents, gap: float, tries: int) -> list | None:
    """One attempt at place_footprints, in the given order; None when a footprint finds no room."""
    placed, outlines = [], []
    for footprint in footprints:
        for _ in range(tries):
            yaw = rng.uniform(0.0, 2 * np.pi)
            turned = _posed(footprint, 0.0, 0.0, yaw)
            room = np.asarray(half_extents) - np.abs(turned).max(axis=0)
            if np.any(room < 0):
                continue
            x, y = rng.uniform(-room[0], room[0]), rng.uniform(-room[1], room[1])
            outline = turned + (x, y)
            if all(_separated(outline, other, gap) for other in outlines):
                placed.append((x, y, yaw))
                outlines.append(outline)
                break
        else:
            return None
    return placed


def place_footprints(rng: np.random.Generator, footprints: list[np.ndarray], half_extents: tuple[float, float],
                     gap: float, tries: int = 200, attempts: int = 20) -> list[tuple[float, float, float]]:
    """(x, y, yaw) for each footprint (K, 2), so that every turned and moved footprint lies inside the
    patch |x| <= half_extents[0], |y| <= half_extents[1] and at least ``gap`` from each other one.

    The largest footprints are placed first; rng draws a yaw, then x and y, for each of up to ``tries``
    places of a footprint, and a layout in which one finds no room starts again, up to ``attempts``
    times. Raises InvalidInputError when none succeeds.
    """
    order = sorted(range(len(footprints)), key=lambda k: -polygon_area(footprints[k]))
    for _ in range(attempts):
        placed = _try_layout(rng, [footprints[k] for k in order], half_extents, gap, tries)
        if placed is not None:
            return [placed[order.index(k)] for k in range(len(footprints))]
    raise InvalidInputError(f"no room for {len(footprints)} objects in a table patch of {2 * half_extents[0]:g} x "
                            f"{2 * half_extents[1]:g} m in {attempts} attempts: use fewer or smaller objects, or a "
                            "larger patch (SceneParams.patch_half_extents)")


def polygon_area(polygon: np.ndarray) -> float:
    """Area of the simple polygon (K, 2) (the shoelace formula), in its unit squared."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * abs(float(x @ np.roll(y, -1) - y @ np.roll(x, -1)))
