"""Why grasp synthesis found no grasp of a mesh, in words a user can act on (sim.parts.grasp_synthesis)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from sim.parts.gripper_fit import Fit

if TYPE_CHECKING:
    from sim.parts.grasp_synthesis import GraspSynthesisParams


def why_not(fit: Fit, params: GraspSynthesisParams) -> str:
    """Why no frame is kept, by the first test that every frame failed."""
    touched = np.isfinite(fit.lo)
    width = fit.width[touched]
    if not width.size:
        return f"nowhere do both pads touch it: no two of its sides face each other within {cone_deg(params):.0f} deg"
    fits = (width >= params.min_width) & (width <= params.widest)
    if not fits.any():
        if width.min() > params.widest:
            return too_wide(width, params)
        if width.max() < params.min_width:
            return (f"every span across it is thinner than the {params.min_width * 1e3:.0f} mm the planner "
                    f"grasps (widest {width.max() * 1e3:.1f} mm)")
        return (f"every span across it is under {params.min_width * 1e3:.0f} mm (a pinch the planner does not "
                f"try) or over the {params.widest * 1e3:.0f} mm the open gripper clears")
    worse, need = fit.areas[touched][fits].min(1), params.min_contact_share * params.pad_area
    if worse.max() < need:
        return (f"the pads would touch too little of it: at best {worse.max() * 1e6:.0f} mm^2 on the worse side, "
                f"{need * 1e6:.0f} mm^2 needed (its sides are too low, rounded or sloped)")
    return (f"the fingers or the palm would hit it at each of the {int((worse >= need).sum())} places where "
            "its sides fit the gripper")


def too_wide(spans: np.ndarray, params: GraspSynthesisParams) -> str:
    if not spans.size:
        return f"no two of its sides face each other within {cone_deg(params):.0f} deg for the pads to close on"
    narrowest = float(spans.min())
    units = "; is the mesh in millimetres? scale it by 0.001" if narrowest > 10 * params.max_opening else ""
    return (f"too wide for the gripper from every side: narrowest span {narrowest * 1e3:.0f} mm, the gripper "
            f"opens {params.max_opening * 1e3:.0f} mm{units}")


def cone_deg(params: GraspSynthesisParams) -> float:
    """The half-angle (degrees) of the friction cone the pads press within."""
    return math.degrees(math.acos(params.cos_cone))

