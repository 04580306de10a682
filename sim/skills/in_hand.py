"""Telling a held part's near-symmetric twins apart: turn it in the hand, look again, judge.

The fixed Kinect sees some parts' telling features edge-on. The chassis' connector window and
gland hole are in its end walls, and a camera 30 degrees off vertical sees those edge-on when the
chassis lies across its view; recognition then reports the twin it could not rule out
(:attr:`psorr.types.Detection.alternatives`). The twins are grasped alike (the grasp is the same
on both), so the robot picks the part from its best pose anyway. After the lift it turns the part
about the vertical, to the yaw at which the twins' rendered depths differ at the most pixels,
looks, and has PSORR refine the pose there and tell the twins apart
(:meth:`sim.skills.perception.Perception.look_at_held`). A look that leaves a twin open is followed by
one from the other side. The look is judged by what the arm leaves in view: the fingers hide some of the
part. If the look settles on another twin, the place is planned again for the part as it is really held.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np

from psorr.sensing.camera import CameraIntrinsics
from psorr.sensing.kinect_noise import KINECT_V1
from psorr.verification.depth_compare import DepthRenderer, differs
from psorr.verification.point_check import check_pose
from psorr.verification.scene_view import SceneView
from sim.control.cell import ArmCell
from sim.errors import UnreachableTargetError
from sim.skills.grasp_planning import angle_deg

SHOW_YAWS_DEG = tuple(range(-150, 181, 30))  # tool turns about the vertical tried for the look
TURN_S = 0.8  # s for the wrist's turn to the look, and back
SETTLE_S = 0.3  # s held still before the look, so the part hangs steady
MAX_OTHER_MOTION = 0.3  # rad any joint may move beyond the turn itself on the way to the look
MIN_SCORE = 0.3  # an in-hand pose scoring less than this is not trusted to overrule the estimate
OTHER_SIDE_DEG = 90.0  # a second look, when the first leaves a twin open, turns at least this far from it


@dataclass(frozen=True)
class InHandLook:
    """What the looks at the held part decided (the last look's, when the first left a twin open).

    Attributes:
        chosen: index into the hypotheses looked at (0: the pose the pick was planned from).
        yaw_deg: the tool's turn about the vertical for the look; telling_pixels: the pixels at which
            the twins' rendered depths differ there (the most of any yaw reachable, for a first look).
        score: the refined pose's score over what the arm leaves in view (:func:`unhidden_score`);
            settled: the look ruled out every other twin.
        looks: how many looks it took (1 or 2).
        nearest: the hypothesis the refined pose is nearest to, whether or not the look settled.
    """

    chosen: int
    yaw_deg: float
    telling_pixels: int
    score: float
    settled: bool
    looks: int = 1
    nearest: int = 0

    def summary(self) -> str:
        """One line for a pick's note."""
        if not self.telling_pixels:
            return "no turn of the wrist to show the part at was reachable"
        verdict = ("held the other way round" if self.chosen else "held as estimated") if self.settled else \
            f"undecided (score {self.score:.2f}), kept the estimate"
        again = ", the second time" if self.looks > 1 else ""
        return (f"looked in the hand (turned {self.yaw_deg:+.0f} deg{again}, {self.telling_pixels} telling px): "
                f"{verdict}")


def turned_about_vertical(T_world_tool: np.ndarray, degrees: float) -> np.ndarray:
    """``T_world_tool`` (4, 4) turned by ``degrees`` about the world's vertical through the tool point."""
    a = np.radians(degrees)
    T = T_world_tool.copy()
    Rz = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    T[:3, :3] = Rz @ T_world_tool[:3, :3]
    return T


def telling_pixels(renderer: DepthRenderer, T_camera_parts: np.ndarray, intrinsics: CameraIntrinsics,
                   radius: float) -> int:
    """How many of the camera's pixels see different depths (by more than 3 Kinect sigmas, or part
    against nothing) for the part at the first pose of ``T_camera_parts`` (K, 4, 4) and at any other;
    the window is a sphere of ``radius`` m about the first pose's origin."""
    centre = T_camera_parts[0, :3, 3]
    u0 = intrinsics.fx * centre[0] / centre[2] + intrinsics.cx
    v0 = intrinsics.fy * centre[1] / centre[2] + intrinsics.cy
    reach = intrinsics.fx * radius / max(centre[2] - radius, 1e-3)
    us = np.arange(max(0, int(u0 - reach)), min(intrinsics.width, int(u0 + reach) + 1))
    vs = np.arange(max(0, int(v0 - reach)), min(intrinsics.height, int(v0 + reach) + 1))
    U, V = (a.ravel() for a in np.meshgrid(us, vs))
    rays = np.column_stack([(U - intrinsics.cx) / intrinsics.fx, (V - intrinsics.cy) / intrinsics.fy,
                            np.ones(len(U))])
    depth = renderer.depth(T_camera_parts, rays)
    sigma = KINECT_V1.depth_sigma(np.where(np.isfinite(depth[0]), depth[0], centre[2]))
    return int(differs(depth[1:], depth[:1], sigma).any(axis=0).sum())


def look_in_hand(cell: ArmCell, perception, part: str, q: np.ndarray, T_world_tool: np.ndarray,
                 T_tool_parts: list[np.ndarray]) -> InHandLook:
    """Turn the held ``part`` about the vertical to show the twins' differences, look, and judge; when
    that look leaves a twin open, look once more from the other side.

    Args:
        cell: the arm, holding the part at ``T_world_tool`` (4, 4) with joints ``q`` (nq,).
        perception: the robot's :class:`sim.skills.perception.Perception` (recognising).
        T_tool_parts: the twins as held, (4, 4) each in the tool frame; the first is the pose the pick
            was planned from.

    The arm ends where it started, at ``q``: a transport planned from the turned wrist can run the
    wrist into its joint limit.
    """
    model = perception.library.model(cell.world.part_types[part])
    hypotheses = np.array(T_tool_parts)
    shows = _reachable_shows(cell, perception, model, q, T_world_tool, hypotheses)
    show = next(shows, None)
    if show is None:
        return InHandLook(0, 0.0, 0, 0.0, False)
    # The fingers hide other samples from the other side, and the faces the first look saw edge-on. Its IK
    # is solved before the first look, against where the person stands now, as the first turn's is.
    other = next((s for s in shows if abs((s.yaw - show.yaw + 180) % 360 - 180) >= OTHER_SIDE_DEG), None)
    seen = _look_from(cell, perception, part, model, hypotheses, show)
    if not seen.settled and other is not None:
        first, seen = seen, replace(_look_from(cell, perception, part, model, hypotheses, other), looks=2)
        # Each look alone found the twin it prefers short of ruling the others out; two views from
        # opposite sides, the fingers hiding different samples in each, preferring the same one settle it.
        if not seen.settled and _trusted(first) and _trusted(seen) and first.nearest == seen.nearest:
            seen = replace(seen, chosen=seen.nearest, settled=True)
    cell.follow([q], TURN_S)
    return seen


@dataclass(frozen=True)
class _Show:
    """A reachable turn of the wrist: ``yaw`` degrees, the ``telling`` pixels there, the tool's pose
    ``T_tool`` (4, 4, world) and the joints ``q`` that reach it."""

    yaw: float
    telling: int
    T_tool: np.ndarray
    q: np.ndarray


def _reachable_shows(cell, perception, model, q, T_world_tool, hypotheses) -> Iterator[_Show]:
    """The turns of SHOW_YAWS_DEG that only the wrist makes, most telling pixels first (then the smallest
    turn); each turn's IK is solved only when the turn is asked for."""
    renderer = DepthRenderer(model.vertices, model.faces)
    T_camera_world = np.linalg.inv(cell.world.T_world_camera)
    options = []
    for yaw in SHOW_YAWS_DEG:
        T_tool = turned_about_vertical(T_world_tool, yaw)
        n = telling_pixels(renderer, T_camera_world @ T_tool @ hypotheses, perception.camera.intrinsics,
                           0.5 * model.diameter)
        options.append((-n, abs(yaw), yaw, T_tool))
    for neg_n, _, yaw, T_tool in sorted(options, key=lambda o: o[:2]):
        try:
            q_show = cell.solve(q, T_tool)
        except UnreachableTargetError:
            continue
        # Only the wrist should turn: a solution on another branch would swing the part through the cell.
        if np.abs(q_show[cell.qadr] - q[cell.qadr]).max() <= np.radians(abs(yaw)) + MAX_OTHER_MOTION:
            yield _Show(float(yaw), -neg_n, T_tool, q_show)


def _look_from(cell, perception, part, model, hypotheses, show: _Show) -> InHandLook:
    """Turn to ``show``, hold still, look, and judge which twin the part is held as."""
    cell.follow([show.q], TURN_S)
    cell.hold(SETTLE_S)
    look = perception.look_at_held(cell.data, part, show.T_tool @ hypotheses[0])
    detection = look.detection
    T_world_part = look.T_world_camera @ detection.T_cloud_model
    # The refined pose is one of the twins: the nearest by rotation.
    turns = [angle_deg((show.T_tool @ H)[:3, :3].T @ T_world_part[:3, :3]) for H in hypotheses]
    score = unhidden_score(look, model)
    nearest = int(np.argmin(turns))
    settled = not detection.alternatives and score >= MIN_SCORE
    return InHandLook(nearest if settled else 0, show.yaw, show.telling, score, settled, nearest=nearest)


def _trusted(look: InHandLook) -> bool:
    return look.score >= MIN_SCORE


def unhidden_score(look, model) -> float:
    """The score of ``look``'s refined pose over only the samples the arm leaves in view: the share of its
    camera-facing samples the measurement supports, less those seen through, where a sample behind the
    fingers counts as hidden, not as unseen (their pixels are removed from the cloud PSORR refines on)."""
    check = check_pose(SceneView(look.with_arm), model.points, model.normals, look.detection.T_cloud_model)
    return check.unblocked_fraction * (1.0 - check.violation_ratio)
