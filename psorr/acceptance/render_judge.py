"""Which of two detections that claim the same pixels explains the measurement better, by render and compare.

The point check scores a pose by the share of the *model* that the scene supports. Two poses that claim
the same pixels, of different models or of one model turned, are then compared by what each shows of
itself, not by what each explains of the scene: a 26 mm cable clip laid inside a knob's measured surface
shows 0.92 of itself, the knob at its true pose 0.81. Rendering both into the scene's pixels, with the
table behind them, and comparing each with the measured depth where the two renders differ, asks the
scene instead: the clip leaves the knob's rim to the table, and the table is not where the sensor measured.
"""

from __future__ import annotations

import numpy as np

from psorr.acceptance.ambiguity import FEATURES_SHOW
from psorr.verification.depth_compare import RESIDUAL_CAP, DepthRenderer, rival_costs
from psorr.verification.scene_view import SceneView

# A verdict needs a cost difference beyond what noise makes on the pixels that tell the two apart: the
# capped squared residual of a pixel on a rendered surface is about chi-square with one degree of freedom,
# so a sum over n pixels spreads by sqrt(2n); two spreads, and never less than one pixel's whole cap.
DECISIVE_SPREADS = 2.0


class RenderJudge:
    """Compares poses of a library's models in one scene ``view``: ``renderers`` maps each model's name to
    its :class:`DepthRenderer`, ``spheres`` to its surface centre (model frame, m) and half diameter (m)."""

    def __init__(self, view: SceneView, renderers: dict[str, DepthRenderer],
                 spheres: dict[str, tuple[np.ndarray, float]]):
        self.view, self.renderers, self.spheres = view, renderers, spheres

    def prefer(self, model_a: str, T_a: np.ndarray, model_b: str, T_b: np.ndarray) -> int:
        """1 when ``model_a`` at ``T_a`` (cloud from model) explains the measured depth clearly better than
        ``model_b`` at ``T_b``, -1 when clearly worse, 0 when the view cannot tell them apart."""
        centres, radii = [], []
        for model, T in ((model_a, T_a), (model_b, T_b)):
            centre, radius = self.spheres[model]
            centres.append(T[:3, :3] @ centre + T[:3, 3])
            radii.append(radius)
        middle = 0.5 * (centres[0] + centres[1])
        reach = 0.5 * float(np.linalg.norm(centres[0] - centres[1])) + max(radii)
        costs, n, evidence = rival_costs(self.view, [(self.renderers[model_a], T_a),
                                                     (self.renderers[model_b], T_b)], middle, reach)
        # A verdict also needs the features that tell the two apart to show, as for a model's twins (decision
        # 0068): one pixel at 3 sigmas and another at 1.5 could otherwise decide (decision 0061).
        if evidence < FEATURES_SHOW:
            return 0
        margin = max(RESIDUAL_CAP, DECISIVE_SPREADS * np.sqrt(2.0 * n))
        if costs[1] - costs[0] > margin:
            return 1
        if costs[0] - costs[1] > margin:
            return -1
        return 0
