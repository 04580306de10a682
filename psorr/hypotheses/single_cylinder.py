"""Pose hypotheses from one cylinder: a scene cylinder matched to a model cylinder by radius and length.

A pipe tee lying on the table shows its run as one long cylinder. Its branch, a short cylinder
seen side on, often comes out of the decomposition as a few narrow planar strips, which no model
cylinder may match: the part then has no pair of primitives to vote for it, though nearly all of it
is in view. One cylinder fixes four of the six degrees of freedom (its axis line); its length fixes
the slide along the axis when it is seen whole. What is left is the roll about the axis, which the
cylinder cannot tell, so each match gives ``roll_steps`` poses for each way along the axis.

Only long cylinders (``min_elongation``) are matched: short ones (hubs, coils, bosses) are on many
parts, so size alone does not say whose they are, and they come with other primitives that pairs use.
And since the cylinder cannot tell the roll, a pose from it is accepted only if the rest of the part,
beyond its long cylinders, passes the point check on its own (``min_support_beyond``): with a tee's
branch hidden, ICP settles on whatever roll puts the branch out of sight.

Like single faces (psorr.hypotheses.single_plane), this is tried only on the scene cylinders that the
pair-based detections leave unexplained, and the poses are ranked by a coarse point check before
the best few go through the same ICP and acceptance as every other hypothesis.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from psorr.checks import params as check
from psorr.errors import InvalidInputError
from psorr.geometry.boxes import orthonormal_frame
from psorr.hypotheses.point_ranking import SinglePrimitiveMatcher
from psorr.hypotheses.primitive_match import RADIUS_TOLERANCE
from psorr.types import Primitive, PrimitiveKind
from psorr.verification.point_check import CheckParams, check_pose


@dataclass(frozen=True)
class SingleCylinderParams:
    """Which cylinders may give a pose on their own. Lengths in metres, areas in m^2.

    A model cylinder counts if its side view (diameter x length) is at least ``min_area`` and it is
    at least ``min_elongation`` diameters long (of our catalog's cylinders, only the pipe tee's run,
    outside and bore, pass both). A scene
    cylinder matches it when its radius is within RADIUS_TOLERANCE of the model's and its length
    within [``min_length_ratio``, ``max_length_ratio``] x the model's (+- ``slack``): a cylinder seen
    whole, or nearly so. Each match gives ``roll_steps`` turns about the axis, both ways along it; at
    most ``max_poses`` poses are made, closest matches first. They are ranked by a coarse point check
    (``check``), and the ``top`` of them (shared out across models) with a score of at least
    ``min_score`` go on to ICP and acceptance, where at least ``min_support_beyond`` of the check's
    points off the model's long cylinders must be supported, as few seen through as the whole part's.
    """

    enabled: bool = True
    roll_steps: int = 12
    max_poses: int = 48
    top: int = 4
    min_score: float = 0.2
    check: CheckParams = field(default_factory=lambda: CheckParams(max_points=400))
    min_area: float = 2e-3
    min_elongation: float = 2.0  # length / diameter
    min_support_beyond: int = 30
    min_length_ratio: float = 0.8
    max_length_ratio: float = 1.15
    slack: float = 0.005

    def __post_init__(self):
        check.flag(self, "enabled")
        check.whole(self, "roll_steps", "max_poses", "top", "min_support_beyond")
        check.within(self, "min_score")
        check.instance(self, "check", CheckParams)
        check.non_negative(self, "min_area", unit=" m^2")
        check.non_negative(self, "slack", unit=" metres")
        check.positive(self, "min_length_ratio", "max_length_ratio", "min_elongation")
        if self.min_length_ratio > self.max_length_ratio:  # no cylinder would ever match
            raise InvalidInputError(f"SingleCylinderParams.min_length_ratio must be <= max_length_ratio, got "
                                    f"{self.min_length_ratio} > {self.max_length_ratio}")


def cylinder_length(cylinder: Primitive) -> float:
    """The cylinder's length along its axis (metres): its box's side along the axis."""
    along = np.abs(cylinder.box.rotation.T @ cylinder.axis)
    return float(np.asarray(cylinder.box.extent)[int(np.argmax(along))])


def axis_frame(cylinder: Primitive, towards: np.ndarray | None = None) -> np.ndarray:
    """(4, 4) frame at the middle of the cylinder's axis segment, z along the axis, x across it: towards
    ``towards`` (a point, such as the sensor) where given, else any direction across the axis."""
    a = cylinder.axis
    middle = cylinder.axis_point + ((np.asarray(cylinder.box.center) - cylinder.axis_point) @ a) * a
    across = (np.asarray(towards, float) - middle) if towards is not None else np.zeros(3)
    across = across - (across @ a) * a
    x = across / np.linalg.norm(across) if np.linalg.norm(across) >= 1e-9 else orthonormal_frame(a)[0]
    frame = np.eye(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = x, np.cross(a, x), a, middle
    return frame


def _rolled(frame: np.ndarray, steps: int) -> np.ndarray:
    """(2 steps, 4, 4): ``frame`` turned about its z by each of ``steps`` even turns, and flipped
    end for end (z and y negated) and turned likewise."""
    out = []
    for flip in (np.eye(4), np.diag([1.0, -1.0, -1.0, 1.0])):
        for angle in 2 * np.pi * np.arange(steps) / steps:
            c, s = np.cos(angle), np.sin(angle)
            turn = np.eye(4)
            turn[:2, :2] = [[c, -s], [s, c]]
            out.append(frame @ flip @ turn)
    return np.array(out)


def _near_cylinder(points: np.ndarray, cylinder: Primitive, length: float, margin: float = 0.003) -> np.ndarray:
    """(N,) which of the (N, 3) points lie on the cylinder's surface or inside it, within ``margin`` metres."""
    F = axis_frame(cylinder)
    local = (points - F[:3, 3]) @ F[:3, :3]
    across, along = np.linalg.norm(local[:, :2], axis=1), np.abs(local[:, 2])
    return (across <= cylinder.radius + margin) & (along <= length / 2 + margin)


class SingleCylinderMatcher(SinglePrimitiveMatcher):
    """The library's model cylinders of at least ``min_area`` side view, ready to be matched to scene ones."""

    def __init__(self, models, params: SingleCylinderParams | None = None):
        self.params = params = params or SingleCylinderParams()
        self.models = list(models)
        self.cylinders = []  # (model index, radius, length, inverse axis frame (4, 4))
        self.beyond = {}  # model index -> (points (N, 3), normals (N, 3)) off its long cylinders
        for index, model in enumerate(models):
            near = np.zeros(len(model.points), dtype=bool)
            for p in model.graph.primitives:
                if p.kind is PrimitiveKind.PLANE:
                    continue
                length = cylinder_length(p)
                if 2 * p.radius * length >= params.min_area and length >= params.min_elongation * 2 * p.radius:
                    self.cylinders.append((index, p.radius, length, np.linalg.inv(axis_frame(p))))
                    near |= _near_cylinder(model.points, p, length)
            if near.any():
                self.beyond[index] = (model.points[~near], model.normals[~near])

    def hypotheses(self, scene_cylinders: list[Primitive]) -> tuple[np.ndarray, np.ndarray]:
        """Poses (K, 4, 4) ``T_cloud_model`` and model indices (K,) from scene cylinders matched by size."""
        p = self.params
        if not p.enabled:
            return np.empty((0, 4, 4)), np.empty(0, dtype=np.int64)
        matches = []  # (size mismatch, order, scene cylinder, model index, model frame inverse)
        for cylinder in scene_cylinders:
            if cylinder.kind is PrimitiveKind.PLANE:
                continue
            length = cylinder_length(cylinder)
            for index, radius, model_length, F_model_inv in self.cylinders:
                if (abs(cylinder.radius - radius) <= RADIUS_TOLERANCE * radius
                        and p.min_length_ratio * model_length - p.slack <= length
                        <= p.max_length_ratio * model_length + p.slack):
                    mismatch = abs(np.log(length / model_length)) + abs(np.log(cylinder.radius / radius))
                    matches.append((mismatch, len(matches), cylinder, index, F_model_inv))
        poses, owners = [], []
        # The closest matches first; the roll is measured from the side that faces the sensor (the origin).
        for _, _, cylinder, index, F_model_inv in sorted(matches, key=lambda m: m[:2]):
            if len(poses) >= p.max_poses:
                break
            for F_scene in _rolled(axis_frame(cylinder, towards=np.zeros(3)), p.roll_steps):
                poses.append(F_scene @ F_model_inv)
                owners.append(index)
        if not poses:
            return np.empty((0, 4, 4)), np.empty(0, dtype=np.int64)
        return np.array(poses[: p.max_poses]), np.array(owners[: p.max_poses], dtype=np.int64)

    def seen_beyond(self, view, model_index: int, T_cloud_model: np.ndarray, check_params: CheckParams,
                    max_violation_ratio: float) -> bool:
        """Does the model's surface off its long cylinders, posed by ``T_cloud_model`` (4, 4) in ``view`` (a
        psorr.verification.scene_view.SceneView), pass the point check on its own: at least
        ``min_support_beyond`` supported points, and no more than ``max_violation_ratio`` of those measured
        seen through?"""
        points, normals = self.beyond[model_index]
        check = check_pose(view, points, normals, T_cloud_model, check_params)
        return check.n_support >= self.params.min_support_beyond and check.violation_ratio <= max_violation_ratio
