"""Pose hypotheses from one plane: a scene face matched to a model face by its size.

Point pairs need two primitives on a part. A Kinect at a metre often returns only one on a
small part (the top of a transformer standing upright; a board lying flat), and the part then
gets no hypothesis at all. One plane fixes three of the six degrees of freedom; its minimum-volume
box fixes the rest up to a half turn (a quarter turn when the face is nearly square): the box
centre is a point, its long side a direction in the plane. A scene plane is therefore matched to
the model planes whose box has the same in-plane sides, and each match gives two (or four)
poses T = F_scene F_model^-1.

The recognizer tries this only on the scene faces that its pair-based detections leave
unexplained, and ranks the poses by a coarse point check: a single face covers too little of a
model's primitive boxes for box verification to rank them. The best few then go through the same
ICP and acceptance as every other hypothesis.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from psorr.checks import params as check
from psorr.errors import InvalidInputError
from psorr.geometry.boxes import orthonormal_frame
from psorr.hypotheses.point_ranking import SinglePrimitiveMatcher
from psorr.types import Primitive, PrimitiveKind
from psorr.verification.point_check import CheckParams

_IN_PLANE_COS = 0.7  # box axes less aligned than this with the normal lie in the plane


@dataclass(frozen=True)
class SinglePlaneParams:
    """Which faces may give a pose on their own. Areas in m^2, slack in metres.

    A scene face must be at least ``min_area``; its in-plane sides must each lie within
    [``min_side_ratio``, ``max_side_ratio``] x the model face's (+- ``slack``): a face seen whole,
    or nearly so. Faces whose sides are within ``square_ratio`` of each other get the quarter turns too.
    At most ``max_poses`` poses are made, from the closest matches of sides first. They are ranked by a coarse
    point check (``check``); the ``top`` of them (shared out across models) with a score of at least
    ``min_score`` go on to ICP and acceptance.
    """

    enabled: bool = True
    max_poses: int = 48
    top: int = 6
    min_score: float = 0.2
    check: CheckParams = field(default_factory=lambda: CheckParams(max_points=400))
    min_area: float = 4e-4
    min_side_ratio: float = 0.75
    max_side_ratio: float = 1.15
    slack: float = 0.005
    square_ratio: float = 0.8

    def __post_init__(self):
        check.flag(self, "enabled")
        check.whole(self, "max_poses", "top")
        check.within(self, "min_score", "square_ratio")
        check.instance(self, "check", CheckParams)
        check.non_negative(self, "min_area", unit=" m^2")
        check.non_negative(self, "slack", unit=" metres")
        check.positive(self, "min_side_ratio", "max_side_ratio")
        if self.min_side_ratio > self.max_side_ratio:  # no face would ever match
            raise InvalidInputError(f"SinglePlaneParams.min_side_ratio must be <= max_side_ratio, got "
                                    f"{self.min_side_ratio} > {self.max_side_ratio}")


def _in_plane_axes(plane: Primitive) -> list[tuple[float, np.ndarray]]:
    """(side length, box axis) of the plane's box axes that lie in its plane, longest first."""
    R, extent, normal = plane.box.rotation, plane.box.extent, plane.normal
    return [(float(extent[k]), R[:, k]) for k in np.argsort(-extent, kind="stable")
            if abs(R[:, k] @ normal) < _IN_PLANE_COS]


def in_plane_sides(plane: Primitive) -> np.ndarray:
    """(2,) the plane's box sides in its plane, longest first (metres)."""
    sides = [side for side, _ in _in_plane_axes(plane)]
    return np.array((sides + [0.0, 0.0])[:2])


def plane_frames(plane: Primitive, quarter_turns: bool) -> np.ndarray:
    """(2 or 4, 4, 4) frames at the plane's box centre: z along its normal, x along its box's long
    in-plane side (either way; and along the short side too with ``quarter_turns``)."""
    n = plane.normal
    in_plane = [axis for _, axis in _in_plane_axes(plane)]
    long_side = in_plane[0] if in_plane else orthonormal_frame(n)[0]
    x = long_side - (long_side @ n) * n
    x /= np.linalg.norm(x)
    directions = [x, -x] + ([np.cross(n, x), -np.cross(n, x)] if quarter_turns else [])
    frames = np.repeat(np.eye(4)[None], len(directions), axis=0)
    for k, d in enumerate(directions):
        frames[k, :3, 0], frames[k, :3, 1], frames[k, :3, 2], frames[k, :3, 3] = d, np.cross(n, d), n, plane.box.center
    return frames


class SinglePlaneMatcher(SinglePrimitiveMatcher):
    """The library's model faces of at least ``min_area``, ready to be matched to scene faces."""

    def __init__(self, models, params: SinglePlaneParams | None = None):
        self.params = params = params or SinglePlaneParams()
        self.models = list(models)
        self.faces = []  # (model index, sides (2,), inverse frame (4, 4)), one frame per face
        for index, model in enumerate(models):
            for p in model.graph.primitives:
                sides = in_plane_sides(p) if p.kind is PrimitiveKind.PLANE else np.zeros(2)
                if sides[0] * sides[1] >= params.min_area:
                    self.faces.append((index, sides, np.linalg.inv(plane_frames(p, False)[0])))

    def hypotheses(self, scene_planes: list[Primitive]) -> tuple[np.ndarray, np.ndarray]:
        """Poses (K, 4, 4) ``T_cloud_model`` and model indices (K,) from scene faces matched by size."""
        p = self.params
        poses, owners = [], []
        if not p.enabled:
            return np.empty((0, 4, 4)), np.empty(0, dtype=np.int64)
        matches = []  # (side mismatch, scene face, model index, model frame inverse, quarter turns)
        for plane in scene_planes:
            if plane.kind is not PrimitiveKind.PLANE:
                continue
            sides = in_plane_sides(plane)
            if sides[0] * sides[1] < p.min_area:
                continue
            for index, model_sides, F_model_inv in self.faces:
                if np.all(sides <= p.max_side_ratio * model_sides + p.slack) and np.all(
                        sides >= p.min_side_ratio * model_sides - p.slack):
                    mismatch = float(np.max(np.abs(np.log(np.maximum(sides, 1e-3) / model_sides))))
                    quarter = model_sides[1] >= p.square_ratio * model_sides[0]
                    matches.append((mismatch, len(matches), plane, index, F_model_inv, quarter))
        # The closest matches first: a face seen whole matches its model face to a few millimetres.
        for _, _, plane, index, F_model_inv, quarter in sorted(matches, key=lambda m: m[:2]):
            if len(poses) >= p.max_poses:
                break
            for F_scene in plane_frames(plane, quarter):
                poses.append(F_scene @ F_model_inv)
                owners.append(index)
        if not poses:
            return np.empty((0, 4, 4)), np.empty(0, dtype=np.int64)
        return np.array(poses[: p.max_poses]), np.array(owners[: p.max_poses], dtype=np.int64)
