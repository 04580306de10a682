"""Poses of one model that put the same surface in the same place: one hypothesis, however it was found.

A rod lies on any of its 64 side facets, a gear on any of its teeth: a part's symmetric resting poses,
searched each on its own, all fit a patch alike, and each would be refined and fitted by acceptance once
more for nothing. Two poses of a model coincide when the turn between them maps the model onto itself (every
sample within the library's facet distance of the mesh, :data:`psorr.library.symmetries.FACET_DISTANCE`,
as its exact symmetries are told). Every such turn keeps the model's surface centroid and second moments
(:mod:`psorr.geometry.surface_moments`), so poses that move either apart are told apart without rendering.
"""

from __future__ import annotations

import numpy as np

from psorr.geometry.surface_moments import area_centroid, second_moments
from psorr.library.symmetries import FACET_DISTANCE
from psorr.verification.depth_compare import DepthRenderer

# Of the model's points: as many as the resting search compares a patch with (OutlineMatcher._FINE_POINTS), so
# that poses it could not tell apart are not kept apart either.
_SAMPLES = 300


class SameSurface:
    """Tells whether two poses of a model coincide; built once per set of models, each model's surface
    measured and rendered on first need."""

    def __init__(self, models):
        self._models = list(models)
        self._renderers: dict[int, DepthRenderer] = {}
        self._moments: dict[int, tuple[np.ndarray, np.ndarray, float]] = {}

    def _surface(self, model: int) -> tuple[np.ndarray, np.ndarray, float]:
        """Model ``model``'s area centroid (3,), second moments (3, 3) and their slack, on first need (a model
        with no pose to compare costs nothing at start-up)."""
        if model not in self._moments:
            m = self._models[model]
            moments = second_moments(m.vertices, m.faces)
            # A surface whose every point x moves by d, at most the facet distance f, changes its second
            # moments mean(x x^T) by at most 2 |mean(x d^T)| + |mean(d d^T)| <= 2 sqrt(mean |x|^2) f + f^2
            # (Cauchy-Schwarz).
            slack = 2.0 * np.sqrt(np.trace(moments)) * FACET_DISTANCE + FACET_DISTANCE**2
            self._moments[model] = (area_centroid(m.vertices, m.faces), moments, slack)
        return self._moments[model]

    def same(self, model: int, T_a: np.ndarray, T_b: np.ndarray) -> bool:
        """Whether poses ``T_a`` and ``T_b`` (4, 4; model -> any frame) of model ``model`` coincide."""
        (centre_a, moment_a), (centre_b, moment_b) = self._placed(model, T_a), self._placed(model, T_b)
        return bool(np.linalg.norm(centre_a - centre_b) <= FACET_DISTANCE
                    and np.linalg.norm(moment_a - moment_b) <= self._surface(model)[2]
                    and self._maps_onto_itself(model, np.linalg.solve(T_a, T_b)))

    def distinct(self, poses: list, model_of, pose_of, limit: int | None = None) -> list:
        """Of ``poses`` (best first), the first ``limit`` (None: all) that coincide with no better one:
        ``model_of(pose)`` is its model's index, ``pose_of(pose)`` its (4, 4) transform."""
        kept: list = []
        models, centres, moments = [], [], []  # of each kept pose: where it puts its model's centroid, moments
        for pose in poses:
            model, T = model_of(pose), pose_of(pose)
            centre, moment = self._placed(model, T)
            if kept:  # the kept poses that could be this one, all at once; rendered only if any
                could = ((np.asarray(models) == model)
                         & (np.linalg.norm(np.asarray(centres) - centre, axis=1) <= FACET_DISTANCE)
                         & (np.linalg.norm(np.asarray(moments) - moment, axis=(1, 2)) <= self._surface(model)[2]))
                if any(self._maps_onto_itself(model, np.linalg.solve(pose_of(kept[k]), T))
                       for k in np.flatnonzero(could)):
                    continue
            kept.append(pose)
            models.append(model)
            centres.append(centre)
            moments.append(moment)
            if len(kept) == limit:
                break
        return kept

    def _placed(self, model: int, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where pose ``T`` puts the model's area centroid (3,), and its second moments (3, 3) there."""
        centre, moments, _ = self._surface(model)
        R = T[:3, :3]
        return R @ centre + T[:3, 3], R @ moments @ R.T

    def _maps_onto_itself(self, model: int, S: np.ndarray) -> bool:
        m = self._models[model]
        subset = m.points[:: max(1, len(m.points) // _SAMPLES)]
        if model not in self._renderers:
            self._renderers[model] = DepthRenderer(m.vertices, m.faces)
        distance = self._renderers[model].distance
        # A tenth first: most turns that keep the centroid and moments (a flat part's half turn about the
        # vertical) move some of those far, and are told apart at a tenth of the cost.
        return all(distance(part @ S[:3, :3].T + S[:3, 3]).max() <= FACET_DISTANCE
                   for part in (subset[::10], subset))
