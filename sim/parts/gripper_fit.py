"""The cell's gripper placed against a part's surface samples: where its pads stop, what they touch,
whether it hits the part, what a pose error leaves of the contact, and which placements repeat others;
the measurements :mod:`sim.parts.grasp_synthesis` searches and ranks with.

A frame is a gripper placement from above: the tool point (metres, model frame; the pads' centres are level
with it) and the horizontal unit closing direction. Coordinates relative to a frame are ``u`` along closing,
``v`` across it and ``w`` up, in metres. Every frame is measured against every sample by the compiled walks
of :mod:`sim.parts.pads_kernel`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import trimesh

from sim.parts.pads_kernel import ahead as ahead_kernel
from sim.parts.pads_kernel import collides, pads_meet

if TYPE_CHECKING:
    from sim.parts.grasp_synthesis import GraspSynthesisParams


@dataclass(frozen=True)
class Surface:
    """Dense samples of a part's surface: points (N, 3) m and unit normals (N, 3), both float32 (the frame x
    sample arrays are where the time goes, and 0.1 um is plenty), and ``area_each`` m^2 of surface a sample."""

    points: np.ndarray
    normals: np.ndarray
    area_each: float

    @classmethod
    def sample(cls, mesh: trimesh.Trimesh, rng: np.random.Generator, params: GraspSynthesisParams) -> Surface:
        count = int(np.clip(math.ceil(mesh.area / params.sample_spacing**2), 100, params.max_samples))
        points, faces = trimesh.sample.sample_surface(mesh, count, seed=int(rng.integers(2**32)))
        return cls(points.astype(np.float32), mesh.face_normals[faces].astype(np.float32), float(mesh.area) / count)


@dataclass(frozen=True)
class Frames:
    """F gripper placements: tool points ``origins`` (F, 3) m and unit closing directions ``closing`` (F, 2)."""

    origins: np.ndarray
    closing: np.ndarray

    def take(self, keep) -> Frames:
        return Frames(self.origins[keep], self.closing[keep])

    @property
    def across(self) -> np.ndarray:
        """(F, 2) horizontal unit vectors across the closing directions."""
        return np.column_stack([self.closing[:, 1], -self.closing[:, 0]])

    def along(self, amount: np.ndarray) -> np.ndarray:
        """(F, 3) offsets of ``amount`` (F,) m along the closing directions."""
        return np.column_stack([self.closing * amount[:, None], np.zeros(len(amount))])


@dataclass(frozen=True)
class Fit:
    """What the pads meet at F frames: ``lo``, ``hi`` (F,) m along closing from the tool point where the pads
    stop (inf, -inf: nothing between them); ``areas`` (F, 2) m^2 of contact at lo and at hi; ``contact``
    (F, 2) m across and above the tool point of the contacts' centroid; ``collides`` (F,) a gripper box
    holds a sample (tested only where asked)."""

    lo: np.ndarray
    hi: np.ndarray
    areas: np.ndarray
    contact: np.ndarray
    collides: np.ndarray

    @property
    def width(self) -> np.ndarray:
        return self.hi - self.lo


def measure(surface: Surface, frames: Frames, params: GraspSynthesisParams, min_area: float | None = None,
            centred: bool = True) -> Fit:
    """What the pads, come down open around each frame's tool point, meet closing; and, for the frames whose
    stops fit the stroke with at least
    ``min_area`` m^2 of contact a side (None: for none), whether the gripper hits the part on the way.
    ``centred``: the tool goes midway between the stops (a planned grasp), else to the frame's origin (a
    grasp planned on a wrong pose: the mirrored fingers then push the part between them)."""
    lo, hi, areas, contact = _pads_meet(surface, frames, params)
    collides = np.zeros(len(lo), bool)
    if min_area is not None:
        test = np.isfinite(lo) & (hi - lo <= params.widest) & (areas.min(1) >= min_area)
        middle = (lo[test] + hi[test]) / 2 if centred else np.zeros(int(test.sum()), lo.dtype)
        collides[test] = _collides(surface, frames.take(test), lo[test] - middle, hi[test] - middle, middle, params)
    return Fit(lo, hi, areas, contact, collides)


def ahead(surface: Surface, seeds: Frames, params: GraspSynthesisParams) -> tuple[np.ndarray, np.ndarray]:
    """For each seed frame (F,), at a surface point: how far (m) along closing the nearest face leaving the
    part lies, antiparallel to the seed's own within the cone (inf if none), found among the samples in a
    tube of 1.5 sample spacings around the ray: the seed's feature's span; and how high (m) the highest
    surface below the seed is where the fingers go beside that feature (0 for the table, else a plate or
    flange the feature stands on)."""
    tube, tol = 1.5 * math.sqrt(surface.area_each), params.contact_tolerance
    reach = params.max_opening / 2 + params.finger_offset[0] + params.finger_half_size[0] + params.clearance
    lane = params.finger_half_size[1] + params.clearance
    return ahead_kernel(surface.points, surface.normals, seeds.origins, seeds.closing, *_offsets(seeds),
                        *np.float32([tube, tol, lane, reach]), params.cos_cone, tube)


def perturbed_share(surface: Surface, frames: Frames, rng: np.random.Generator,
                    params: GraspSynthesisParams) -> np.ndarray:
    """(F,) mean over seeded pose errors of the worse pad's contact as a share of a pad's face (0 where the
    gripper would hit the part or not hold it)."""
    k = params.perturbations
    turn = -np.radians(params.pose_error_deg) * rng.choice([-1.0, 1.0], k)
    heading = rng.uniform(0.0, 2 * np.pi, k)
    shift = params.pose_error * np.column_stack([np.cos(heading), np.sin(heading)])
    # The part turned by a about the grasp point and shifted by t is, relative to the part, the gripper
    # turned by -a and moved by -R(-a) t.
    R = np.stack([np.stack([np.cos(turn), -np.sin(turn)], 1), np.stack([np.sin(turn), np.cos(turn)], 1)], 1)
    closing = np.einsum("kij,fj->fki", R, frames.closing).reshape(-1, 2)
    moved = np.column_stack([-np.einsum("kij,kj->ki", R, shift), np.zeros(k)])
    origins = (frames.origins[:, None, :] + moved[None]).reshape(-1, 3)
    fit = measure(surface, Frames(origins, closing), params, surface.area_each, centred=False)
    held = np.isfinite(fit.lo) & (fit.width <= params.widest) & ~fit.collides
    share = np.where(held, fit.areas.min(1), 0.0) / params.pad_area
    return share.reshape(len(frames.origins), k).mean(1)


def unique(frames: Frames, params: GraspSynthesisParams) -> Frames:
    """The frames less those repeating an earlier one within half the duplicate tolerances (as quantised):
    the survivors still differ, at a fraction of the work."""
    angle = np.arctan2(frames.closing[:, 1], frames.closing[:, 0]) / np.radians(params.duplicate_angle_deg / 2)
    keys = np.column_stack([np.round(frames.origins / (params.duplicate_distance / 2)), np.round(angle)])
    return frames.take(np.sort(np.unique(keys, axis=0, return_index=True)[1]))


def distinct(frames: Frames, params: GraspSynthesisParams) -> list[int]:
    """Indices of the frames (best first) left after dropping each that repeats a better one: closer than
    ``duplicate_distance`` horizontally, overlapping by over half the pads' height, closing within
    ``duplicate_angle_deg`` (either way)."""
    kept: list[int] = []
    same_angle = math.cos(math.radians(params.duplicate_angle_deg))
    for i, (origin, closing) in enumerate(zip(frames.origins, frames.closing)):
        near = (np.hypot(*(frames.origins[kept, :2] - origin[:2]).T) <= params.duplicate_distance) \
            & (np.abs(frames.origins[kept, 2] - origin[2]) <= params.pad_half_size[2]) \
            & (np.abs(frames.closing[kept] @ closing) >= same_angle)
        if not near.any():
            kept.append(i)
    return kept


def _offsets(frames: Frames) -> list[np.ndarray]:
    """(F,) float32 each tool point's coordinate along closing and across it: a sample's ``u`` is
    ``closing . (x, y) - offset`` in float32 (and ``v`` the same across)."""
    return [(frames.origins[:, 0] * d[:, 0] + frames.origins[:, 1] * d[:, 1]).astype(np.float32)
            for d in (frames.closing, frames.across)]


def _pads_meet(surface: Surface, frames: Frames, params: GraspSynthesisParams) -> tuple:
    """``lo``, ``hi``, ``areas`` and ``contact`` of :class:`Fit` for the frames (the compiled walk of
    :mod:`sim.parts.pads_kernel`; the samples between the pads' faces as they come down open)."""
    lo, hi, counts, sums, touching = pads_meet(
        surface.points, surface.normals, frames.origins, frames.closing, *_offsets(frames),
        *np.float32([params.pad_half_size[1], params.pad_half_size[2], params.max_opening / 2,
                     params.contact_tolerance]), params.cos_cone)
    return lo, hi, counts * surface.area_each, sums / np.maximum(touching, 1)[:, None]


def box_limits(params: GraspSynthesisParams) -> np.ndarray:
    """(15,) float32 limits (m) of the gripper's boxes about the tool, in the order
    :func:`sim.parts.pads_kernel.collides` unpacks them: the strip that can hold a hit (across, lowest up), the
    pads (across, nearest and farthest along closing, lowest up), the fingers (across, nearest and farthest,
    lowest up), the palm (across, along, lowest up), the fingers' top and their inner face past a pad's stop."""
    m, half_open = params.clearance, params.max_opening / 2
    pad_t, pad_w, pad_h = params.pad_half_size
    finger_t, finger_w, finger_h = params.finger_half_size
    finger_x, finger_z = params.finger_offset
    palm_x, palm_y, palm_z = params.palm_half_size
    finger_in, finger_out = finger_x - finger_t - m, half_open + finger_x + finger_t + m
    finger_low, finger_top = finger_z - finger_h - m, finger_z + finger_h + m
    return np.float32([max(pad_w, finger_w, palm_y) + m, min(-pad_h - m, finger_low), pad_w + m, half_open - m,
                       half_open + 2 * pad_t + m, -pad_h - m, finger_w + m, half_open + finger_in, finger_out,
                       finger_low, palm_y + m, palm_x + m, params.palm_height - palm_z - m, finger_top, finger_in])


def _collides(surface: Surface, frames: Frames, lo: np.ndarray, hi: np.ndarray, middle: np.ndarray,
              params: GraspSynthesisParams) -> np.ndarray:
    """(F,) whether a sample lies in a gripper box, the tool ``middle`` (F,) m along closing from the frame's
    origin: descending fully open, then closing until the pads stop at ``lo`` and ``hi`` (F,) m from it (the
    compiled walk of :mod:`sim.parts.pads_kernel`)."""
    return collides(surface.points, frames.origins, frames.closing, *_offsets(frames), lo, hi, middle,
                    box_limits(params))
