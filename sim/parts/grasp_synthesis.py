"""Parallel-jaw grasps from a part's mesh alone, for the cell's gripper closing on it from straight above.

1. **Seeds.** Surface points whose normal is within the pads' friction cone of horizontal, whose inward
   horizontal ray reaches a face leaving the part, antiparallel within the cone, within the stroke.
2. **Placements.** The pads' faces (20 x 35 mm) go across the part on each seed's ray, level with the seed
   or as low as keeps them off the table, and also just above a plate or flange the seed's feature stands
   on. The part's dense surface samples in the pads' band set where the pads stop (the width) and what
   they touch: the samples near each stop whose normal is in the cone, times the area a sample stands for.
   Each placement is centred between its stops, and also onto its contacts, and measured again.
3. **Kept** if both contacts are large enough and no sample lies in the gripper's boxes (pads, fingers and
   palm of ``assets/robot/arm.xml``) descending fully open, then closing onto the part.
4. **Ranked** by the worse contact left when the part lies off by the recognizer's typical error (seeded
   shifts and turns), less a penalty for the distance from the centre of mass; near-duplicates dropped.

The measurements are :mod:`sim.parts.gripper_fit`'s; the constants are discussed in
docs/decisions/0054-grasp-synthesis.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np
import trimesh

from psorr.checks import params as check
from psorr.errors import InvalidInputError
from psorr.geometry.solids import centre_of_mass
from sim.errors import SimInputError
from sim.parts.grasp import Grasp
from sim.parts.gripper_fit import Fit, Frames, Surface, ahead, distinct, measure, perturbed_share, unique

__all__ = ["GraspSynthesisParams", "synthesise_grasps"]

_TABLE_TOL = 1e-6  # m the mesh's lowest point may lie off z = 0


@dataclass(frozen=True)
class GraspSynthesisParams:
    """The gripper's geometry (metres; defaults from ``assets/robot/arm.xml``) and the search's settings
    (docs/decisions/0054-grasp-synthesis.md).

    Attributes:
        max_opening: largest opening between the pads (the "gripper" actuator's ctrlrange); the fingers
            descend this far open, as :func:`sim.skills.pick.approach` does.
        min_width: narrowest span grasped (:func:`sim.skills.grasp_planning.plan_grasp` tries none under it).
        pad_half_size: pad box half sizes: thickness (along closing), width, height ("left_pad"); the pad's
            centre is level with the tool point and its face at the opening.
        finger_half_size: finger box half sizes, same axes ("left_finger_collision").
        finger_offset: the finger box's centre beyond the pad's face, and above the tool point.
        palm_half_size: palm box half sizes along closing, across and up ("gripper_collision").
        palm_height: the palm box's centre above the tool point.
        friction: the pads' sliding friction coefficient (the "pad" default class).
        cone_share: share of the friction angle used as the friction cone (below 1: conservative).
        contact_tolerance: a sample this close to where a pad stops touches it.
        min_contact_share: least contact on each side, as a share of a pad's face.
        clearance: margin grown on every gripper box when testing for collisions.
        table_clearance: least height of the pads' lower ends above the table (grasp_planning.PAD_CLEARANCE).
        sample_spacing: mean spacing of the dense surface samples, at most ``max_samples`` of them.
        max_samples: cap on the dense samples; a larger part is sampled more sparsely.
        seeds: surface points drawn as seeds.
        pose_error: shift of the recognizer's typical pose error that the ranking allows for.
        pose_error_deg: turn (degrees, about the vertical) of that error.
        perturbations: seeded shifted-and-turned poses each grasp is ranked on.
        com_weight: score lost (in shares of a pad's face) per footprint half-diagonal off the centre of mass.
        duplicate_distance: grasps closer than this horizontally, overlapping in height ...
        duplicate_angle_deg: ... and closing within this angle are one grasp.
        max_grasps: most grasps returned.
    """

    max_opening: float = 0.08
    min_width: float = 0.008
    pad_half_size: tuple[float, float, float] = (0.004, 0.01, 0.0175)
    finger_half_size: tuple[float, float, float] = (0.005, 0.011, 0.0325)
    finger_offset: tuple[float, float] = (0.013, 0.015)
    palm_half_size: tuple[float, float, float] = (0.065, 0.027, 0.035)
    palm_height: float = 0.0825
    friction: float = 1.5
    cone_share: float = 0.5
    contact_tolerance: float = 0.001
    min_contact_share: float = 0.05
    clearance: float = 0.001
    table_clearance: float = 0.0015
    sample_spacing: float = 0.001
    max_samples: int = 60_000
    seeds: int = 1000
    pose_error: float = 0.003
    pose_error_deg: float = 3.0
    perturbations: int = 8
    com_weight: float = 0.5
    duplicate_distance: float = 0.005
    duplicate_angle_deg: float = 15.0
    max_grasps: int = 8

    def __post_init__(self):
        try:
            for name, size in (("pad_half_size", 3), ("finger_half_size", 3), ("finger_offset", 2),
                               ("palm_half_size", 3)):
                _check_sizes(self, name, size)
            check.positive(self, "max_opening", "min_width", "palm_height", "contact_tolerance", "sample_spacing",
                           "pose_error", "duplicate_distance", unit=" metres")
            check.non_negative(self, "clearance", "table_clearance", unit=" metres")
            check.non_negative(self, "pose_error_deg", "com_weight")
            check.positive(self, "friction", "cone_share", "min_contact_share")
            check.within(self, "cone_share", "min_contact_share")
            check.within(self, "duplicate_angle_deg", low=0, high=90)
            check.whole(self, "max_samples", minimum=100)
            check.whole(self, "seeds", "perturbations", "max_grasps")
        except InvalidInputError as exc:  # the sim's inputs raise the sim's error (still an InvalidInputError)
            raise SimInputError(str(exc)) from None
        if self.min_width >= self.max_opening:
            raise SimInputError(f"GraspSynthesisParams.min_width ({self.min_width} m) must be less than "
                                f"max_opening ({self.max_opening} m)")

    @property
    def cos_cone(self) -> float:
        """Cosine of the friction cone's half-angle: ``cone_share`` of atan(``friction``)."""
        return math.cos(self.cone_share * math.atan(self.friction))

    @property
    def pad_area(self) -> float:
        """m^2 of a pad's face."""
        return 4.0 * self.pad_half_size[1] * self.pad_half_size[2]

    @property
    def widest(self) -> float:
        """Widest span grasped (m): the opening less the clearance on both sides."""
        return self.max_opening - 2 * self.clearance

    @property
    def lowest(self) -> float:
        """Lowest tool point (m above the table): the pads' lower ends ``table_clearance`` above it."""
        return self.pad_half_size[2] + self.table_clearance


def _check_sizes(params: GraspSynthesisParams, name: str, size: int) -> None:
    value = getattr(params, name)
    numbers = isinstance(value, tuple) and all(isinstance(v, Real) and not isinstance(v, bool) for v in value)
    if not (numbers and len(value) == size and all(math.isfinite(v) and v > 0 for v in value)):
        raise InvalidInputError(f"GraspSynthesisParams.{name} must be a tuple of {size} positive numbers of "
                                f"metres, got {value!r}")


def synthesise_grasps(mesh: trimesh.Trimesh, rng: np.random.Generator,
                      params: GraspSynthesisParams = GraspSynthesisParams()) -> tuple[Grasp, ...]:
    """Top-down parallel-jaw grasps of ``mesh``, best first, named "synth_0", "synth_1", ...

    Args:
        mesh: the part in metres, model frame, resting upright on the table plane z = 0 (+z up).
        rng: the source of every random draw; the same seed gives the same grasps bit for bit.
        params: gripper geometry and search settings.

    Returns:
        At most ``params.max_grasps`` grasps, each with approach (0, 0, -1), a horizontal closing direction,
        ``point`` midway between the contacts at the pads' centre height and ``width`` between the contact
        faces (m, model frame).

    Raises:
        SimInputError: the mesh is no trimesh or does not rest on z = 0; or no grasp survives, saying why
            (too wide or too thin for the gripper, too little contact, or the fingers would hit the part).
    """
    _check_mesh(mesh)
    surface = Surface.sample(mesh, rng, params)
    seeds = _seed_frames(mesh, surface, rng, params)
    frames = _recentre(seeds, measure(surface, seeds, params), params)
    fit = measure(surface, frames, params, params.min_contact_share * params.pad_area)
    ok = _fits(fit, params) & ~fit.collides
    if not ok.any():
        raise SimInputError(f"no top-down grasp of the mesh: {_why_not(fit, params)}")
    fit, frames = Fit(fit.lo[ok], fit.hi[ok], fit.areas[ok], fit.contact[ok], fit.collides[ok]), frames.take(ok)
    frames = Frames(frames.origins + frames.along((fit.lo + fit.hi) / 2), frames.closing)  # the tool between
    off_centre = params.com_weight * _off_centre(frames, mesh)
    # The distinct placements (each the best of its neighbours, nominally) are ranked on perturbed contact.
    order = np.argsort(off_centre - fit.areas.min(1) / params.pad_area, kind="stable")
    order = order[distinct(frames.take(order), params)][: 4 * params.max_grasps]
    score = perturbed_share(surface, frames.take(order), rng, params) - off_centre[order]
    best = order[np.argsort(-score, kind="stable")][: params.max_grasps]
    return tuple(Grasp(f"synth_{k}", frames.origins[i], (0.0, 0.0, -1.0), (*frames.closing[i], 0.0),
                       float(fit.width[i])) for k, i in enumerate(best))


def _check_mesh(mesh) -> None:
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise SimInputError(f"grasp synthesis needs a trimesh.Trimesh with faces, got {type(mesh).__name__}")
    if not np.isfinite(mesh.vertices).all():
        raise SimInputError("the mesh has non-finite vertices; repair the file")
    if abs(float(mesh.bounds[0, 2])) > _TABLE_TOL:
        raise SimInputError(f"the mesh must rest on the table plane z = 0, but its lowest point is at z = "
                            f"{mesh.bounds[0, 2]:.6g} m; put it upright first, e.g. with "
                            "psorr.synthetic.resting.stable_rests(mesh)[0].T_table_model")


def _seed_frames(mesh: trimesh.Trimesh, surface: Surface, rng: np.random.Generator,
                 params: GraspSynthesisParams) -> Frames:
    """Placements from surface points whose normal is within the cone of horizontal and whose feature's span
    fits the stroke, closing inward."""
    points, faces = trimesh.sample.sample_surface(mesh, params.seeds, seed=int(rng.integers(2**32)))
    normals = mesh.face_normals[faces]
    level = np.hypot(normals[:, 0], normals[:, 1])
    flat = level >= params.cos_cone
    if not flat.any():
        raise SimInputError(f"no top-down grasp of the mesh: no side of it is within {_cone_deg(params):.0f} deg "
                            "of vertical for the pads to press on")
    seeds = Frames(points[flat], -normals[flat, :2] / level[flat, None])
    span, floor = ahead(surface, seeds, params)
    found = span <= params.max_opening
    if not found.any():
        raise SimInputError(f"no top-down grasp of the mesh: {_too_wide(span[np.isfinite(span)], params)}")
    return _placements(seeds.take(found), span[found], floor[found], params)


def _placements(seeds: Frames, span: np.ndarray, floor: np.ndarray, params: GraspSynthesisParams) -> Frames:
    """The seeds' (F, at surface points) frames in two places along their rays: the tool over the seed's
    feature (``span`` (F,) m long: the pads come down around it alone), and the open pads' face just
    outside the seed (they close on all they span from there); at two heights where they differ: the pads
    reaching down to the table, and the pads above the highest surface (``floor`` (F,) m) beside the
    feature."""
    shift = np.concatenate([span / 2, np.full(len(span), params.max_opening / 2 - params.clearance)])
    xy = np.tile(seeds.origins[:, :2], (2, 1)) + np.tile(seeds.closing, (2, 1)) * shift[:, None]
    low = np.tile(np.maximum(seeds.origins[:, 2], params.lowest), 2)
    raised = np.tile(np.maximum(seeds.origins[:, 2], floor + params.lowest), 2)
    twice, closing = raised > low, np.tile(seeds.closing, (2, 1))
    origins = np.concatenate([np.column_stack([xy, low]), np.column_stack([xy[twice], raised[twice]])])
    return unique(Frames(origins, np.concatenate([closing, closing[twice]])), params)


def _recentre(frames: Frames, fit: Fit, params: GraspSynthesisParams) -> Frames:
    """The frames that fit, moved midway between their stops (which leaves the pads' band as it was), and
    those touching on both sides moved onto their contacts' centroid too (which can gain contact or lose
    it), closing turned to a canonical sign; repeats dropped."""
    ok = np.isfinite(fit.lo) & (fit.areas > 0).all(1)
    middle = frames.origins + frames.along((np.where(ok, fit.lo, 0.0) + np.where(ok, fit.hi, 0.0)) / 2)
    onto = middle + np.column_stack([frames.across * fit.contact[:, :1], fit.contact[:, 1]])
    onto[:, 2] = np.maximum(onto[:, 2], params.lowest)
    closing = frames.closing
    flip = (closing[:, 0] < -1e-12) | ((np.abs(closing[:, 0]) <= 1e-12) & (closing[:, 1] < 0))  # d, -d: one grasp
    closing = np.where(flip[:, None], -closing, closing)
    fits = _fits(fit, params)
    origins, closing = np.concatenate([middle[fits], onto[ok]]), np.concatenate([closing[fits], closing[ok]])
    return unique(Frames(origins, closing), params)


def _fits(fit: Fit, params: GraspSynthesisParams) -> np.ndarray:
    """(F,) whether a frame's stops fit the stroke and give both pads enough contact."""
    width = fit.width
    return (np.isfinite(fit.lo) & (width >= params.min_width) & (width <= params.widest)
            & (fit.areas.min(1) >= params.min_contact_share * params.pad_area))


def _why_not(fit: Fit, params: GraspSynthesisParams) -> str:
    """Why no frame is kept, by the first test that every frame failed."""
    touched = np.isfinite(fit.lo)
    width = fit.width[touched]
    if not width.size:
        return f"nowhere do both pads touch it: no two of its sides face each other within {_cone_deg(params):.0f} deg"
    fits = (width >= params.min_width) & (width <= params.widest)
    if not fits.any():
        if width.min() > params.widest:
            return _too_wide(width, params)
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


def _too_wide(spans: np.ndarray, params: GraspSynthesisParams) -> str:
    if not spans.size:
        return f"no two of its sides face each other within {_cone_deg(params):.0f} deg for the pads to close on"
    narrowest = float(spans.min())
    units = "; is the mesh in millimetres? scale it by 0.001" if narrowest > 10 * params.max_opening else ""
    return (f"too wide for the gripper from every side: narrowest span {narrowest * 1e3:.0f} mm, the gripper "
            f"opens {params.max_opening * 1e3:.0f} mm{units}")


def _cone_deg(params: GraspSynthesisParams) -> float:
    return math.degrees(math.acos(params.cos_cone))


def _off_centre(frames: Frames, mesh: trimesh.Trimesh) -> np.ndarray:
    """(F,) horizontal distance of each tool point from the centre of mass, in footprint half-diagonals."""
    com = centre_of_mass(mesh)
    return np.hypot(*(frames.origins[:, :2] - com[:2]).T) / (0.5 * np.hypot(*mesh.extents[:2]))
