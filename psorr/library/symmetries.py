"""A model's near-symmetries: turns and slides that map it almost onto itself, found once per model.

A sheet-metal tray with a connector window at one end is, to a point-pair matcher, the same
tray turned end for end. :func:`near_symmetries` finds the turns about its principal axes (through
the centroid of its samples; half turns, and turns by 360/n degrees, as a knob of three lobes has),
each settled onto the model by ICP, that move its surface by little on average (an L bracket's legs
swap about their bisector, a few degrees off its principal axes); exact symmetries qualify too, and
:func:`exact_symmetries` tells them apart. :func:`composed_turns` adds the products of two of those turns
that lie about no principal axis (a three-spoked knob's half turns about its other spokes).
:func:`near_continuous_axis` finds an axis about which any turn is a near-symmetry (a flanged hub,
whose yaw only its bolt holes fix). :func:`near_uniform_direction` finds a direction along which the
part slides almost onto itself (a U-channel along its length, which only its two end faces fix).
Choosing between such poses in a scene is :mod:`psorr.acceptance.ambiguity`'s work.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from psorr.geometry.rotations import rotation_angle, rotation_vector, turn, turn_about_line
from psorr.types import PrimitiveKind
from psorr.verification.depth_compare import DepthRenderer

NEAR_MEAN_DISTANCE = 0.03  # x model diameter: turns moving the surface less than this on average are near-symmetries
EXACT_DISTANCE = 2e-4  # m: a turn moving no sample further than this from the mesh is an exact symmetry
# m: a half turn moving no sample further than this from the mesh is a symmetry in all but its facets (a
# round part's tessellation moves 0.6 mm); the least feature that breaks one in the catalog moves 7 mm.
FACET_DISTANCE = 1e-3
AXIS_TEST_DEGREES = (7.0, 19.0, 37.0, 90.0, 143.0)  # turns that must all be near-symmetries for a near-continuous axis
# A slide by TEST_SHIFT x diameter that moves the surface by less than UNIFORM_LIMIT x the slide on average
# (90% of the surface slides onto itself) makes a direction near-uniform.
TEST_SHIFT, UNIFORM_LIMIT = 0.05, 0.1
# A half turn that moves fewer than FEATURE_SHARE of the samples further than FEATURE_MOVE from the surface
# is exact but for small features (the chassis' window and gland hole).
FEATURE_MOVE, FEATURE_SHARE = 0.002, 0.1
# Besides the half turns, the turns by 360 k / n degrees for n from 3 to MAX_ORDER, as
# psorr.synthetic.mesh_symmetry tries them when it grades poses (a three-lobed knob turned by 120 degrees).
MAX_ORDER = 8
PARALLEL_COS = np.cos(np.radians(10.0))  # a principal axis within 10 degrees of a near-continuous axis is it
_ACROSS_SIN = np.sin(np.radians(10.0))  # ... and a direction within 10 degrees of square to an axis is across it
_LARGEST_GROUP = 60  # the icosahedral group's order, the largest finite rotation group but the cyclic and dihedral


def near_symmetries(points: np.ndarray, diameter: float, limit: float = NEAR_MEAN_DISTANCE,
                    axis: np.ndarray | None = None, directions: np.ndarray | None = None) -> np.ndarray:
    """(K, 4, 4) model-frame near-symmetries S about principal axes through the samples' centroid, each
    settled by ICP of S(points) onto points, whose mean nearest-sample distance is below ``limit`` x
    ``diameter``: a half turn about each axis, and about an axis the part is round across (in its second
    moments, as any n-fold symmetry makes it) the turns of the lowest order n (3 to MAX_ORDER) whose every
    turn k / n settles near its own angle. One per distinct turn; K may be 0. No turns of order n > 2 are
    tried about ``axis`` (a near-continuous axis, whose every angle is searched on its own).

    Where two principal moments are round (a square bar's section, a cube's all three), the principal axes
    in their plane are any pair; there the ``directions`` that lie in it (the normals of the model's faces,
    its cylinders' axes: a drilled cube's turns lie about them) are tried as well.

    Args:
        points: (N, 3) even surface samples of the model, metres.
        diameter: the model's diameter, metres.
        axis: (3,) a direction, model frame, about which to try half turns only; None for none.
        directions: (D, 3) unit directions, model frame, to try where the principal axes are undetermined.
    """
    centroid = points.mean(axis=0)
    covariance = np.cov((points - centroid).T)
    moments, axes = np.linalg.eigh(covariance)
    tree = cKDTree(points)
    subset = points[:: max(1, len(points) // 3000)]
    found = []

    def settled(direction: np.ndarray, angle: float) -> tuple[np.ndarray, float]:
        S = turn_about_line(direction, angle, centroid)
        # A part that is not quite symmetric (an L bracket with legs of 60 and 50 mm) has its
        # principal axes a few degrees off the turn that swaps its halves; settle onto that turn.
        S, distance = _settled(S, subset, tree)
        return S, float(distance.mean())

    def add(S: np.ndarray, mean: float) -> None:
        if not any(np.linalg.norm(S[:3, :3] - F[:3, :3]) < 0.1 for _, F in found):
            found.append((mean, S))

    more = _undetermined(directions, moments, axes, limit * diameter)
    for i, direction in enumerate([*axes.T, *more]):
        S, mean = settled(direction, np.pi)
        if mean < limit * diameter:
            add(S, mean)
        about_axis = axis is not None and abs(float(direction @ axis)) > PARALLEL_COS
        across = np.delete(moments, i) if i < 3 else _moments_across(covariance, direction)
        if not about_axis and _round_in_plane(across, limit * diameter):
            # A turn off by delta moves samples at the rms radius r by r delta: at most the limit.
            drift = limit * diameter / np.sqrt(across.sum())
            for S, mean in _cyclic_turns(direction, settled, limit * diameter, drift):
                add(S, mean)
    # Those that map the part best onto itself first: of turns alike up to a symmetry the first stands for all
    # (distinct_up_to_exact), and a hexagonal standoff's half turn about an arbitrary principal axis of its round
    # section settled 5.7 degrees off the face's normal it stood for (decision 0033).
    found.sort(key=lambda pair: pair[0])
    return np.array([S for _, S in found]).reshape(-1, 4, 4)


def composed_turns(turns: np.ndarray, exact: np.ndarray, points: np.ndarray, diameter: float,
                   axis: np.ndarray | None = None, limit: float = NEAR_MEAN_DISTANCE) -> np.ndarray:
    """(K, 4, 4) the near-symmetries that products of two of ``turns`` (from :func:`near_symmetries`) make and
    they lack: a three-spoked knob's half turns about its other two spokes, which are no principal axis (its
    turns by a third times the half turn found). ``exact`` (len(turns),) marks the exact symmetries, whose
    products with each other are exact too and are not tried. A product counts when it moves the samples
    ``points`` (N, 3) by less than ``limit`` x ``diameter`` on average, is not a turn about the near-continuous
    ``axis`` (3,; searched on its own), and lies at least half the least turn tried from the identity and
    from every turn kept: products of near turns drift by a few degrees, and two near half turns about axes a
    little apart make a small spin, which moves any part little."""
    tree = cKDTree(points)
    subset = points[:: max(1, len(points) // 3000)]
    least = np.pi / MAX_ORDER
    kept, added = list(turns), []
    for i, j in ((i, j) for i in range(len(turns)) for j in range(len(turns)) if not (exact[i] and exact[j])):
        S = turns[i] @ turns[j]
        direction = rotation_vector(S[:3, :3])
        if np.linalg.norm(direction) < least or any(rotation_angle(S[:3, :3] @ K[:3, :3].T) < least for K in kept):
            continue
        if axis is not None and abs(float(direction @ axis)) > PARALLEL_COS * np.linalg.norm(direction):
            continue
        if float(tree.query(subset @ S[:3, :3].T + S[:3, 3])[0].mean()) < limit * diameter:
            kept.append(S)
            added.append(S)
    return np.array(added).reshape(-1, 4, 4)


def _cyclic_turns(direction: np.ndarray, settled, limit: float, drift: float) -> list[tuple[np.ndarray, float]]:
    """The turns k / n (k = 1 .. n-1), each with its mean distance, of the lowest order n (3 to MAX_ORDER) about
    ``direction`` that all settle (``settled(direction, angle)`` -> (S, mean distance)) below ``limit`` (m)
    within ``drift`` (rad) of their own angle; none if no order does. A turn that ICP moves further has slid
    towards another symmetry (a square bar's 120 degrees towards its 90) and stopped short of it."""
    for n in range(3, MAX_ORDER + 1):
        group = []
        for k in range(1, n):
            angle = 2.0 * np.pi * k / n
            S, mean = settled(direction, angle)
            if mean >= limit or rotation_angle(S[:3, :3] @ turn(direction, angle).T) > drift:
                break
            group.append((S, mean))
        else:
            return group
    return []


def _moments_across(covariance: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """(2,) the principal moments (m^2) of ``covariance`` (3, 3) in the plane across the unit ``direction``."""
    basis = np.linalg.svd(np.eye(3) - np.outer(direction, direction))[0][:, :2]
    return np.linalg.eigvalsh(basis.T @ covariance @ basis)


def _undetermined(directions: np.ndarray | None, moments: np.ndarray, axes: np.ndarray, move: float) -> list:
    """The unit ``directions`` (D, 3) that lie where the principal ``axes`` (3, 3, columns) are undetermined by
    their ``moments`` (3,): in the plane of two round moments (across the third axis), or anywhere when all three
    are round; one of each within PARALLEL_COS of another or of a principal axis."""
    if directions is None or not len(directions):
        return []
    round_across = [i for i in range(3) if _round_in_plane(np.delete(moments, i), move)]
    if not round_across:
        return []
    kept = [axes[:, i] for i in range(3)]
    for d in np.asarray(directions, dtype=float):
        d = d / np.linalg.norm(d)
        in_plane = len(round_across) == 3 or any(abs(float(d @ axes[:, i])) < _ACROSS_SIN for i in round_across)
        if in_plane and all(abs(float(d @ k)) < PARALLEL_COS for k in kept):
            kept.append(d)
    return kept[3:]


def _round_in_plane(moments: np.ndarray, move: float) -> bool:
    """Could a turn other than a half turn about an axis be a near-symmetry, given the two principal
    moments (2,) (m^2) across it? A turn by theta changes the in-plane covariance by sqrt(2) |a - b| |sin theta|,
    and one that moves the samples by ``move`` (m) on average changes it by about 2 r move, r the rms radius
    in the plane; with |sin theta| at least sin 45 degrees (orders up to 8) the moments may differ by 2 r move."""
    a, b = moments
    return abs(a - b) <= 2.0 * np.sqrt(max(a + b, 0.0)) * move


def _settled(S: np.ndarray, points: np.ndarray, tree: cKDTree, iterations: int = 15) -> tuple[np.ndarray, np.ndarray]:
    """The self-map S (4, 4) refined by point-to-point ICP of S(points) onto the model's own
    samples (``tree``), and the final nearest-sample distances (N,) in metres."""
    sparse = points[::3]  # the fit needs far fewer points than the final distances
    for _ in range(iterations):
        moved = sparse @ S[:3, :3].T + S[:3, 3]
        _, nearest = tree.query(moved)
        target = tree.data[nearest]
        mu_m, mu_t = moved.mean(axis=0), target.mean(axis=0)
        U, _, Vt = np.linalg.svd((moved - mu_m).T @ (target - mu_t))
        D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
        step = np.eye(4)
        step[:3, :3] = Vt.T @ D @ U.T
        step[:3, 3] = mu_t - step[:3, :3] @ mu_m
        S = step @ S
        if np.abs(step[:3, 3]).max() < 1e-6 and np.trace(step[:3, :3]) > 3.0 - 1e-10:
            break  # settled
    distance, _ = tree.query(points @ S[:3, :3].T + S[:3, 3])
    return S, distance


def near_continuous_axis(model, renderer: DepthRenderer,
                         limit: float = NEAR_MEAN_DISTANCE) -> tuple[np.ndarray, np.ndarray] | None:
    """The axis (a point (3,) on it, its direction (3,)) about which every test turn of ``model`` is a
    near-symmetry (mean distance below ``limit`` x diameter) but not all are exact symmetries (a
    turned sample lands more than ``EXACT_DISTANCE`` from the mesh), or None.

    A flanged hub is such a part: turned by any angle it is the same hub except for its bolt holes.
    A plain bushing is exactly symmetric, and no turn of it needs telling apart. The candidates are
    the model's cylinder axes and its principal axes; a cylinder's axis is the sharper estimate
    (principal axes of a squat part are barely determined), and the best-fitting candidate wins.
    """
    points = model.points
    centroid = points.mean(axis=0)
    _, axes = np.linalg.eigh(np.cov((points - centroid).T))
    candidates = [(p.axis_point, p.axis) for p in model.graph.primitives if p.kind is PrimitiveKind.CYLINDER]
    candidates += [(centroid, axis) for axis in axes.T]
    subset = points[:: max(1, len(points) // 1500)]
    best, best_mean = None, np.inf
    for point, axis in candidates:
        means, largest = [], 0.0
        for a in AXIS_TEST_DEGREES:  # most candidates fail the first turn or two
            distance = renderer.distance((subset - point) @ turn(axis, np.radians(a)).T + point)
            means.append(distance.mean())
            largest = max(largest, float(distance.max()))
            if means[-1] >= limit * model.diameter:
                break
        else:
            if largest > EXACT_DISTANCE and np.mean(means) < best_mean:
                best, best_mean = (np.asarray(point, float), np.asarray(axis, float)), float(np.mean(means))
    return best


def near_uniform_direction(model, renderer: DepthRenderer) -> np.ndarray | None:
    """The unit direction (3,), model frame, among the principal axes of ``model``'s samples, along
    which a slide by TEST_SHIFT x diameter moves its surface least, if that is below UNIFORM_LIMIT x
    the slide on average; else None. Of the catalog only the U-channel has one (0.06); the chassis,
    whose end walls fix it, and the circuit board come next at 0.16 and 0.13."""
    points = model.points[:: max(1, len(model.points) // 1500)]
    _, axes = np.linalg.eigh(np.cov((points - points.mean(axis=0)).T))
    shift = TEST_SHIFT * model.diameter
    moved = np.array([renderer.distance(points + shift * axis).mean() for axis in axes.T]) / shift
    k = int(np.argmin(moved))
    return axes[:, k] if moved[k] < UNIFORM_LIMIT else None


def exact_symmetries(renderer: DepthRenderer, points: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """(K,) bool: does each turn (K, 4, 4) map every sample of ``points`` (N, 3) to within FACET_DISTANCE of
    the mesh? Such a turn is a symmetry: its poses are the same part, with nothing to tell apart."""
    subset = points[:: max(1, len(points) // 1500)]
    return np.array([renderer.distance(subset @ S[:3, :3].T + S[:3, 3]).max() <= FACET_DISTANCE for S in turns],
                    dtype=bool)


def distinct_up_to_exact(turns: np.ndarray, exact: np.ndarray) -> np.ndarray:
    """(K', 4, 4) one of each set of ``turns`` (K, 4, 4) that give the same poses: S and S' where S^-1 S' is one of
    the group the ``exact`` symmetries (E, 4, 4) generate, so that a pose turned by either looks the same (a
    drilled cube's 16 near-symmetric turns are two poses of its hole, across the view and along it). Rotations
    within half the least turn tried of each other are one; the first of each set is kept."""
    # trace(A B^T) = 1 + 2 cos(angle between A and B): at least this, they are one.
    same = 1.0 + 2.0 * np.cos(np.pi / MAX_ORDER)
    group = np.eye(3)[None]
    generators = np.array([E[:3, :3] for E in exact]).reshape(-1, 3, 3)
    while len(turns) and len(generators) and len(group) < _LARGEST_GROUP:  # closed under composition
        products = np.einsum("aij,bjk->abik", np.concatenate([generators, group]), group).reshape(-1, 3, 3)
        new = []
        for C in products:
            if np.einsum("ij,nij->n", C, np.concatenate([group, *new])).max() < same:
                new.append(C[None])
        if not new:
            break
        # A round part's exact turns make no finite group; none of the point groups has more than 60.
        group = np.concatenate([group, *new])[:_LARGEST_GROUP]
    kept: list[np.ndarray] = []
    for S in turns:
        if all(np.einsum("ij,nij->n", K[:3, :3].T @ S[:3, :3], group).max() < same for K in kept):
            kept.append(S)
    return np.array(kept).reshape(-1, 4, 4)


def exact_but_features(points: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """(K,) bool: does each turn (K, 4, 4) move fewer than FEATURE_SHARE of the model's ``points`` (N, 3)
    further than FEATURE_MOVE from the samples?"""
    tree = cKDTree(points)
    return np.array([(tree.query(points @ S[:3, :3].T + S[:3, 3])[0] > FEATURE_MOVE).mean() < FEATURE_SHARE
                     for S in turns], dtype=bool)
