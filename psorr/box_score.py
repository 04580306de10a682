"""Box verification of pose hypotheses (PSORR paper, section 2.1.4).

A hypothesis moves the minimum-volume boxes of the model's primitives into the
scene; it scores by how much of them the boxes of agreeing scene primitives
cover. Only primitives of the same kind and orientation count: a wall's box
overlapping a floor's says nothing for the pose.

All hypotheses of a scene are scored in one batch: every (hypothesis, model
primitive, scene primitive) triple that survives the orientation test and the
separating-axis test gets its exact box intersection (psorr.box_batch), with
no Python loop over hypotheses or pairs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.box_batch import intersection_ratios
from psorr.box_overlap import boxes_to_arrays, overlap_candidates
from psorr.primitive_match import RADIUS_TOLERANCE
from psorr.types import PrimitiveKind

_COS_AGREE = np.cos(np.radians(20.0))


@dataclass(frozen=True)
class PrimitiveArrays:
    """A list of N primitives as arrays: box centres (N, 3), rotations (N, 3, 3) and extents (N, 3)
    in metres; is_plane (N,); direction (N, 3), a plane's normal or a cylinder's axis; radius (N,),
    metres (0 for planes); weight (N,), the number of points (surface area, as samples are even)."""

    centers: np.ndarray
    rotations: np.ndarray
    extents: np.ndarray
    is_plane: np.ndarray
    direction: np.ndarray
    radius: np.ndarray
    weight: np.ndarray

    @classmethod
    def of(cls, primitives) -> PrimitiveArrays:
        prims = list(primitives)
        plane = np.array([p.kind is PrimitiveKind.PLANE for p in prims], dtype=bool)
        centers, rotations, extents = boxes_to_arrays(p.box for p in prims)
        return cls(centers=centers, rotations=rotations, extents=extents, is_plane=plane,
                   direction=np.array([p.normal if f else p.axis for p, f in zip(prims, plane)]).reshape(-1, 3),
                   radius=np.array([0.0 if f else p.radius for p, f in zip(prims, plane)]),
                   weight=np.array([p.n_points for p in prims], dtype=float))


def box_scores(model_prims: PrimitiveArrays, poses: np.ndarray, scene: PrimitiveArrays,
               thickness: float) -> np.ndarray:
    """(H,) scores in [0, 1] of H poses (H, 4, 4) T_cloud_model of one model.

    A pose's score is the area-weighted mean, over the model primitives that face
    the sensor (cylinders always do), of the share of each primitive's box that the best
    agreeing scene primitive's box covers. Agreeing: the same kind, orientation within
    20 degrees, and a cylinder's radius within RADIUS_TOLERANCE. Only boxes that meet
    as they are count; their share is then measured with both thickened to at least
    ``thickness`` metres (psorr.box_overlap.intersection_ratio), so that it reflects the
    in-plane overlap rather than sub-millimetre offsets along a face's normal.
    """
    H, P, S = len(poses), len(model_prims.weight), len(scene.weight)
    if H == 0 or P == 0 or S == 0:
        return np.zeros(H)
    R, t = poses[:, :3, :3], poses[:, :3, 3]
    centers = np.einsum("hij,pj->hpi", R, model_prims.centers) + t[:, None, :]          # (H, P, 3)
    rotations = np.einsum("hij,pjk->hpik", R, model_prims.rotations)                     # (H, P, 3, 3)
    direction = np.einsum("hij,pj->hpi", R, model_prims.direction)                       # (H, P, 3)
    # A plane facing away from the sensor (at the origin) can match no scene box.
    facing = ~model_prims.is_plane | (np.einsum("hpi,hpi->hp", direction, centers) < 0)
    cos = np.einsum("hpi,si->hps", direction, scene.direction)
    same_kind = model_prims.is_plane[:, None] == scene.is_plane[None, :]                 # (P, S)
    radius_gap = np.abs(model_prims.radius[:, None] - scene.radius[None, :])
    radius_ok = radius_gap < RADIUS_TOLERANCE * model_prims.radius[:, None]
    agree = np.where(model_prims.is_plane[:, None], cos > _COS_AGREE, (np.abs(cos) > _COS_AGREE) & radius_ok)
    agree &= same_kind & facing[:, :, None]
    extents = np.broadcast_to(model_prims.extents, (H, P, 3))
    near = overlap_candidates(centers.reshape(-1, 3), rotations.reshape(-1, 3, 3), extents.reshape(-1, 3),
                              scene.centers, scene.rotations, scene.extents)
    flat, s = np.nonzero(near & agree.reshape(H * P, S))
    covered = np.zeros(H * P)
    if len(flat):
        ratios = intersection_ratios(centers.reshape(-1, 3)[flat], rotations.reshape(-1, 3, 3)[flat],
                                     extents.reshape(-1, 3)[flat], scene.centers[s], scene.rotations[s],
                                     scene.extents[s], thickness)
        np.maximum.at(covered, flat, ratios)
    weights = facing * model_prims.weight                                                 # (H, P)
    total = weights.sum(axis=1)
    score = (covered.reshape(H, P) * weights).sum(axis=1) / np.where(total > 0, total, 1.0)
    return np.where(total > 0, score, 0.0)
