"""Choosing between a model's near-symmetric poses in a scene.

A sheet-metal tray with a connector window at one end is, to a point-pair matcher, the same
tray turned end for end: every primitive has its twin. Verification at the primitive level
cannot tell the two poses apart, and the turned one is often accepted. The difference lies in
small features (a window, a gland hole, a row of holes) that only a dense point check sees.

:mod:`psorr.library.symmetries` finds, once per model, its near-symmetric turns, an axis of
near-continuous symmetry (a flanged hub) and a direction it slides along almost onto itself (a
U-channel): ICP cannot place such a part along it, and a pose from primitive pairs can start a
centimetre or two off there, or several when others hide part of its faces
(:meth:`NearSymmetryResolver.slide_onto_surface` then finds it along the data before ICP).
:class:`NearSymmetryResolver` re-fits each turned pose with ICP, searches the turn about the axis or
the slide along the direction, and keeps the pose whose rendered depth (:mod:`psorr.verification.depth_compare`)
agrees best with the measurement where the candidates differ. When the features are hidden the
poses cannot be told apart: the original is kept, and the turns the view did not rule out are
returned with it, for a detection's ``alternatives``.
"""

from __future__ import annotations

import weakref

import numpy as np

from psorr.acceptance.icp import refine_icp
from psorr.acceptance.projective import refine_projective
from psorr.geometry.rotations import turn_about_line
from psorr.geometry.surface_moments import surface_area
from psorr.library.derived import derived
from psorr.library.symmetries import (
    AXIS_TEST_DEGREES,
    composed_turns,
    distinct_up_to_exact,
    exact_but_features,
    exact_symmetries,
    near_continuous_axis,
    near_symmetries,
    near_uniform_direction,
)
from psorr.types import PrimitiveKind, UnfixedTurn
from psorr.verification.depth_compare import (
    DISCRIMINATIVE_SIGMAS,
    DepthRenderer,
    footprint,
    residual_costs,
    twin_costs,
)
from psorr.verification.point_check import CheckParams, PoseCheck, check_pose
from psorr.verification.scene_view import SceneView

AXIS_COARSE_DEG, AXIS_FINE_DEG = 4.0, 0.5
# Slides are searched up to SLIDE_REACH x diameter, in SLIDE_COARSE steps, then SLIDE_FINE steps around the best.
SLIDE_REACH, SLIDE_COARSE, SLIDE_FINE = 0.16, 0.02, 0.005
# x diameter: how far a candidate is slid to find the measured surface (slide_onto_surface), and in what
# steps (ICP, after it, pairs points up to 12 mm apart: 0.09 of the U-channel's diameter)
SLIDE_SEARCH, SLIDE_SEARCH_STEP = 0.4, 0.05
DENSE_CHECK = CheckParams(max_points=6000)
FOOTPRINT_SAMPLES = 3000  # model samples a pose is projected by, to find the pixels it can cover
# A turned pose replaces the original only when its residual is clearly lower; when the features
# that tell them apart are hidden the residuals tie, and recognition's own choice stands.
SWITCH_RATIO = 0.9
# A turned pose whose residual is within this factor of the chosen one's is not ruled out: the view
# did not show enough of the features (reported as Detection.alternatives). Over the chassis' views
# where its end walls are seen edge-on (Table 1's full views, the demo cell's), the wrong end costs
# 0.97-1.39 times the right one; where they face the sensor (Table 1's partial views), 1.6-3.0.
UNRESOLVED_RATIO = 1.5
# A twin's features show when the cost the wrong pose adds in expectation, E (squared sigmas summed over the
# pixels), stands DISCRIMINATIVE_SIGMAS of its own noise, 2 sqrt(E), above zero: E >= 36. A hole through a plate
# thinner than the per-pixel bar shows over many pixels; a slot narrower than a pixel, met by a ray or two, does
# not (decision 0068).
FEATURES_SHOW = (2 * DISCRIMINATIVE_SIGMAS) ** 2

# A model's near-symmetries (turns, which of them are exact but for features, axis, slide direction), by
# model object: Models are immutable.
_FOUND: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _inputs(model) -> tuple:
    """Everything of ``model`` its near-symmetries are found from: samples, mesh, diameter, primitives' directions."""
    return (model.points, model.normals, model.vertices, model.faces, model.diameter, _directions(model),
            [p.kind is PrimitiveKind.PLANE for p in model.graph.primitives])


def _directions(model) -> np.ndarray:
    """(P, 3) the model's planes' normals and cylinders' axes."""
    return np.reshape([p.normal if p.kind is PrimitiveKind.PLANE else p.axis for p in model.graph.primitives], (-1, 3))


def _encode_found(found: tuple) -> dict:
    turns, exact, axis, slide, area, reach = found
    arrays = {"turns": turns, "exact_but_features": exact, "area": area, "axis_reach": reach}
    if axis is not None:
        arrays["axis_point"], arrays["axis_direction"] = axis
    if slide is not None:
        arrays["slide"] = slide
    return arrays


def _decode_found(arrays) -> tuple:
    axis = (arrays["axis_point"], arrays["axis_direction"]) if "axis_point" in arrays else None
    return (arrays["turns"], arrays["exact_but_features"], axis, arrays.get("slide"), float(arrays["area"]),
            float(arrays["axis_reach"]))


def _axis_reach(points: np.ndarray, axis: tuple[np.ndarray, np.ndarray] | None) -> float:
    """How far (m) a turn by one radian about ``axis`` (a point on it, its direction) carries the sample of
    ``points`` (N, 3) furthest from it; 0 without an axis."""
    if axis is None:
        return 0.0
    off = points - axis[0]
    return float(np.linalg.norm(off - np.outer(off @ axis[1], axis[1]), axis=1).max())


def _near_turns(model, renderer: DepthRenderer, axis: np.ndarray | None) -> np.ndarray:
    """(K, 4, 4) the model's near-symmetric turns that are no exact symmetry: those found about its principal
    axes (and about its faces' normals and cylinders' axes where those are undetermined), and their products
    (:func:`composed_turns`), one of each that an exact symmetry makes alike. Exact symmetries (the transformer's,
    the bushing's) need no choosing: their poses are one part."""
    turns = near_symmetries(model.points, model.diameter, axis=axis, directions=_directions(model))
    exact = exact_symmetries(renderer, model.points, turns)
    more = composed_turns(turns, exact, model.points, model.diameter, axis)
    more_exact = exact_symmetries(renderer, model.points, more)
    return distinct_up_to_exact(np.concatenate([turns[~exact], more[~more_exact]]),
                                np.concatenate([turns[exact], more[more_exact]]))


class NearSymmetryResolver:
    """Chooses between a model's near-symmetric poses in a scene by render and compare.

    Built once per model: its near-symmetric turns (:func:`near_symmetries`) and its axis of
    near-continuous symmetry (:func:`near_continuous_axis`), if any. :meth:`resolve` takes a refined
    detection and returns the pose, among those the model cannot tell apart by its larger surfaces,
    whose rendered depth agrees best with the measurement where the candidates differ.
    """

    def __init__(self, model):
        self.model = model
        self.renderer = DepthRenderer(model.vertices, model.faces)
        found = _FOUND.get(model)
        if found is None:  # about 0.2 s a model: once per model object, and kept on disk for the next process
            found = _FOUND[model] = derived("near-symmetries", _inputs(model), lambda: self._find(model),
                                            _encode_found, _decode_found)
        self.turns, self._exact_but_features, self.axis, self.slide, self._area, self._axis_reach = found
        self._centre = model.points.mean(axis=0)

    def _find(self, model) -> tuple:
        """(turns, which are exact but for features, axis or None, slide direction or None, area, axis reach)."""
        axis = near_continuous_axis(model, self.renderer)
        turns = _near_turns(model, self.renderer, None if axis is None else axis[1])
        return (turns, exact_but_features(model.points, turns), axis, near_uniform_direction(model, self.renderer),
                surface_area(model.vertices, model.faces), _axis_reach(model.points, axis))

    @property
    def has_broad_twins(self) -> bool:
        """Does a near-symmetric turn move much of the surface (an L bracket's legs swapped), not only small features
        (the chassis' window)? Then the point check, too, tells the twin poses apart."""
        return bool((~self._exact_but_features).any())

    def resolve(self, view: SceneView, T_cloud_model: np.ndarray,
                icp_distance: float) -> tuple[np.ndarray, PoseCheck, tuple[np.ndarray, ...]]:
        """The best pose (4, 4), its dense :class:`PoseCheck`, and the near-symmetric poses (4, 4) the
        view could not rule out (its turns within UNRESOLVED_RATIO of the best's residual)."""
        T = T_cloud_model
        if self.slide is not None:
            T = self._best_slide(view, T)
        if self.axis is not None:
            T = self._best_turn_about_axis(view, T)
        alternatives = ()
        if len(self.turns):
            T, alternatives = self._best_half_turn(view, T, icp_distance)
        m = self.model
        return T, check_pose(view, m.points, m.normals, T, DENSE_CHECK), alternatives

    def unfixed_turn(self, view: SceneView, T_cloud_model: np.ndarray) -> UnfixedTurn | None:
        """The model's near-continuous axis, when the view shows nothing that fixes the turn about it at pose
        ``T_cloud_model`` (4, 4): turned by each of the axis's test angles, the model renders alike where the
        sensor measured (the evidence between the renders, as for a twin, stays under FEATURES_SHOW). None
        when the model has no such axis, or the view fixes the turn."""
        if self.axis is None:
            return None
        poses = np.concatenate([T_cloud_model[None], self._about_axis(T_cloud_model, np.array(AXIS_TEST_DEGREES))])
        _, evidence = twin_costs(view, self.renderer, poses, [(0, k) for k in range(1, len(poses))],
                                 self._centre_of(T_cloud_model), 0.5 * self.model.diameter, self._covered(view, poses))
        return UnfixedTurn(*self.axis) if evidence.max() < FEATURES_SHOW else None

    def fit_surface(self, view: SceneView, T_cloud_model: np.ndarray, reach: float) -> np.ndarray:
        """The pose (4, 4) near ``T_cloud_model`` that fits the model's surface to the measured depth
        (:func:`refine_projective`), over the pixels within ``reach`` m of the model's bounding sphere."""
        return refine_projective(view, self.renderer, T_cloud_model, self._centre_of(T_cloud_model),
                                 0.5 * self.model.diameter + reach)

    def _costs(self, view: SceneView, poses: np.ndarray, discriminative: bool = True,
               sweep: float = 0.0) -> np.ndarray:
        return residual_costs(view, self.renderer, poses, self._centre_of(poses[0]), 0.5 * self.model.diameter,
                              discriminative, sweep, self._covered(view, poses))

    def _covered(self, view: SceneView, poses: np.ndarray) -> np.ndarray:
        """The pixels some of ``poses`` can render the model in: a rod turned about its own axis sweeps a
        strip, not the square around its bounding sphere (70,000 pixels a pose for a 250 mm rod)."""
        samples = self.model.points[:: max(1, len(self.model.points) // FOOTPRINT_SAMPLES)]
        spacing = np.sqrt(self._area / len(samples))
        return footprint(view, np.concatenate([samples @ T[:3, :3].T + T[:3, 3] for T in poses]), spacing)

    def _centre_of(self, T: np.ndarray) -> np.ndarray:
        return T[:3, :3] @ self._centre + T[:3, 3]

    def _about_axis(self, T: np.ndarray, degrees: np.ndarray) -> np.ndarray:
        point, axis = self.axis
        poses = np.repeat(T[None], len(degrees), axis=0)
        for k, a in enumerate(degrees):
            poses[k] = T @ turn_about_line(axis, np.radians(a), point)
        return poses

    def _best_turn_about_axis(self, view: SceneView, T: np.ndarray) -> np.ndarray:
        # Coarse to fine: a whole turn in AXIS_COARSE_DEG steps, then AXIS_FINE_DEG steps around the best.
        # Every pixel of the window counts. Counting only those where a pose differs from the first by
        # 3 sigma made the cost of a turn depend on which other turns were tried (pixels just under the
        # bar drop out), and the fine step's winner was then 2-3 degrees off on a hub 1.15 m away
        # (the cell's camera). Over all pixels a turn has one cost, whatever other turns are tried.
        coarse = np.arange(0.0, 360.0, AXIS_COARSE_DEG)
        sweep = self._axis_reach * np.radians(AXIS_COARSE_DEG)  # at the sample furthest from the axis
        best = coarse[int(np.argmin(self._costs(view, self._about_axis(T, coarse), False, sweep)))]
        fine = np.concatenate([[0.0], best + np.arange(-AXIS_COARSE_DEG, AXIS_COARSE_DEG + 1e-9, AXIS_FINE_DEG)])
        poses = self._about_axis(T, fine)
        return poses[int(np.argmin(self._costs(view, poses, discriminative=False)))]

    def _slid(self, T: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        poses = np.repeat(T[None], len(offsets), axis=0)
        poses[:, :3, 3] += np.outer(offsets * self.model.diameter, T[:3, :3] @ self.slide)
        return poses

    def _best_slide(self, view: SceneView, T: np.ndarray) -> np.ndarray:
        coarse = np.arange(-SLIDE_REACH, SLIDE_REACH + 1e-9, SLIDE_COARSE)
        poses = self._slid(T, np.concatenate([[0.0], coarse]))  # the pose found comes first: costs differ from it
        costs = self._costs(view, poses, sweep=SLIDE_COARSE * self.model.diameter)
        best = coarse[int(np.argmin(costs[1:]))]
        fine = np.concatenate([[0.0], best + np.arange(-SLIDE_COARSE, SLIDE_COARSE + 1e-9, SLIDE_FINE)])
        poses = self._slid(T, fine)
        costs = self._costs(view, poses)
        k = int(np.argmin(costs))
        # As with the turns: a slide must clearly lower the residual, or the end faces are hidden.
        return poses[k] if costs[k] < SWITCH_RATIO * costs[0] else T

    def slide_onto_surface(self, view: SceneView, T: np.ndarray, params: CheckParams) -> np.ndarray:
        """For a part that slides almost onto itself (:func:`near_uniform_direction`): the pose along that
        direction, within SLIDE_SEARCH x diameter of ``T``, whose point check scores best. A pose from plane
        centroids is off along a channel by as much as a third of its length when others hide part of
        its faces, beyond both ICP's reach and the render-and-compare slide's."""
        if self.slide is None:
            return T
        poses = self._slid(T, np.arange(-SLIDE_SEARCH, SLIDE_SEARCH + 1e-9, SLIDE_SEARCH_STEP))
        m = self.model
        scores = [check_pose(view, m.points, m.normals, P, params).score for P in poses]
        return poses[int(np.argmax(scores))]

    def _best_half_turn(self, view: SceneView, T: np.ndarray,
                        icp_distance: float) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        m = self.model
        turned = []
        for S in self.turns:
            pose = refine_icp(view, m.points, m.normals, T @ S, icp_distance)
            turned.append(refine_icp(view, m.points, m.normals, pose, icp_distance / 3))
        turned = np.array(turned)
        ratios = np.full(len(turned), np.inf)  # each turned pose's cost over the original's
        exact = self._exact_but_features
        for k in np.flatnonzero(exact):
            # ICP fits the turned pose a millimetre or two from the original, and along a part's outline
            # that misalignment costs more than small features where they cover a few dozen pixels (Table
            # 1's full views). So only the features' pixels count: where each pose, turned in place, renders
            # differently from itself. Outside them the two are the same part in nearly the same place.
            S = self.turns[k]
            costs, evidence = twin_costs(view, self.renderer, np.array([T, turned[k], T @ S, turned[k] @ S]),
                                         [(0, 2), (1, 3)], self._centre_of(T), 0.5 * self.model.diameter)
            # Where the pose found and its own twin render alike, the view does not show the features:
            # the poses tie, whatever the turned pose, refitted a millimetre away, renders differently
            # from its twin over a few pixels (decisions 0067 and 0068).
            if evidence[0] < FEATURES_SHOW:
                # The twin is then the pose found, turned in place: it fits the view as that one does, and the
                # refit, free to slide on the faces they share, drifted (a three-spoked knob's turn by up to
                # 0.21 of its diameter, tilted off the table).
                ratios[k], turned[k] = 1.0, T @ S
            elif costs[0] > 0:
                ratios[k] = costs[1] / costs[0]
        if (~exact).any():
            costs = self._costs(view, np.concatenate([T[None], turned[~exact]]))
            ratios[~exact] = costs[1:] / costs[0] if costs[0] > 0 else np.inf
        k = int(np.argmin(ratios))
        # Ties (the features that tell the poses apart are hidden) keep the pose recognition found.
        if ratios[k] < SWITCH_RATIO:
            best, others = turned[k], [(T, 1.0 / ratios[k])] + [(P, r / ratios[k]) for j, (P, r) in
                                                                 enumerate(zip(turned, ratios)) if j != k]
        else:
            best, others = T, list(zip(turned, ratios))
        return best, tuple(P for P, r in others if r < UNRESOLVED_RATIO)
