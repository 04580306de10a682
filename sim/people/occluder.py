"""A simulated human occluder: a person at the table edge opposite the robot reaches over the table.

The person stands beyond the table's +x edge (the robot stands at the -x edge), facing -x, and
reaches with the right arm, made of capsules (``upper_arm``, ``forearm``, ``hand``) plus a
``torso`` capsule, over the table towards a point ``target_xy`` on it, pauses, and withdraws. The
hand passes ``hand_height`` above the table top, between the camera and the parts, so it
occludes them in the depth image. Motion follows minimum-jerk profiles.

Frames and units: world frame of ``sim/world/assembly.py`` (metres, z up), times in seconds. Each
capsule's body frame sits at the capsule's centre with its z axis along the capsule (MuJoCo's
capsule axis), so a body pose fully places its geom. The bodies are mocap bodies; the world
adds them (``sim.world.WorldConfig.occluder``) and drives them with ``World.apply_occluder``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from psorr.geometry.rotations import cross  # not np.cross: the person is posed 50 times a second
from sim.errors import SimInputError

PREFIX = "human/"
SEGMENTS = ("torso", "upper_arm", "forearm", "hand")
"""Capsule names (without ``PREFIX``); each is one mocap body and one geom of the same name."""
RADII = {"torso": 0.12, "upper_arm": 0.05, "forearm": 0.042, "hand": 0.045}
"""Capsule radii, metres."""
UPPER_ARM, FOREARM, HAND = 0.32, 0.30, 0.12
"""Segment lengths (m): shoulder-elbow, elbow-wrist, and the hand's capsule axis (wrist to finger tips)."""
TORSO_LENGTH = 0.55
"""Torso capsule axis length (m), hip to neck base."""

# Shoulder at rest and at the peak of the reach, relative to (edge_x, shoulder_y, table_top); the person leans in.
_SHOULDER_REST = np.array([0.30, 0.0, 0.60])
SHOULDER_REACH = np.array([0.10, 0.0, 0.45])  # public: sim.people.human judges clearance from the shoulder at the peak
_HAND_REST = np.array([0.34, 0.02, 0.02])  # hand centre hanging by the thigh, beyond the edge
_LIFT = 0.12  # extra height of the hand at mid-path, so it clears the table edge (m)
_TORSO_SIDE = -0.19  # torso axis y relative to the right shoulder (the person faces -x: right is +y)


def minimum_jerk(tau: float) -> float:
    """Minimum-jerk blend 10 t^3 - 15 t^4 + 6 t^5 of ``tau`` clipped to [0, 1]; 0 -> 0, 1 -> 1, zero end rates."""
    t = min(max(float(tau), 0.0), 1.0)
    return t * t * t * (10.0 + t * (-15.0 + 6.0 * t))


@dataclass(frozen=True)
class ReachSchedule:
    """One reach of the human over the table (seconds, metres, world frame).

    Attributes:
        start_s: time the reach starts; before it the arm rests beyond the table edge.
        reach_s: duration of the reach towards the target (> 0).
        pause_s: time the hand stays over the target (>= 0).
        withdraw_s: duration of the withdrawal back to rest (> 0).
        target_xy: (2,) table-top point to occlude.
        hand_xy: (2,) where the hand's centre is at the peak: over ``target_xy`` as seen from the
            camera when one was given to :meth:`sample` (else equal to ``target_xy``).
        hand_height: height of the hand's centre above the table top at the peak.
        shoulder_y: y of the person's right shoulder (where they stand along the edge).
        edge_x: x of the table edge the person stands at (the +x edge, opposite the robot).
        table_top: z of the table top.
    """

    start_s: float
    reach_s: float
    pause_s: float
    withdraw_s: float
    target_xy: tuple[float, float]
    hand_xy: tuple[float, float]
    hand_height: float
    shoulder_y: float
    edge_x: float
    table_top: float

    def __post_init__(self):
        for name in ("target_xy", "hand_xy"):
            xy = tuple(float(v) for v in np.asarray(getattr(self, name), dtype=float).ravel())
            if len(xy) != 2 or not all(map(math.isfinite, xy)):
                raise SimInputError(f"{name} must be 2 finite numbers (x, y) in metres, got {getattr(self, name)}")
            object.__setattr__(self, name, xy)
        if min(self.start_s, self.pause_s) < 0 or min(self.reach_s, self.withdraw_s) <= 0:
            raise SimInputError(
                f"need start_s, pause_s >= 0 and reach_s, withdraw_s > 0 (seconds); got {self.start_s}, "
                f"{self.pause_s}, {self.reach_s}, {self.withdraw_s}"
            )
        if self.hand_height <= 0:
            raise SimInputError(f"hand_height must be > 0 m above the table top, got {self.hand_height}")

    @property
    def peak_s(self) -> tuple[float, float]:
        """(begin, end) of the pause, seconds: the hand is at ``hand_xy`` throughout."""
        begin = self.start_s + self.reach_s
        return begin, begin + self.pause_s

    @property
    def end_s(self) -> float:
        """Time the arm is back at rest, seconds."""
        return self.peak_s[1] + self.withdraw_s

    @classmethod
    def sample(
        cls,
        rng: np.random.Generator,
        table_size: tuple[float, float],
        table_top: float,
        targets=None,
        eye=None,
        start_s: tuple[float, float] = (0.0, 1.0),
        reach_s: tuple[float, float] = (0.6, 1.2),
        pause_s: tuple[float, float] = (0.3, 1.0),
        withdraw_s: tuple[float, float] = (0.6, 1.2),
        hand_height: tuple[float, float] = (0.15, 0.25),
    ) -> ReachSchedule:
        """Draw a schedule from ``rng`` (its only randomness): durations and hand height uniform in their ranges.

        Args:
            rng: the randomness.
            table_size: (x, y) of the table top, centred on the world's z axis; the person stands at +x.
            table_top: z of the table top.
            targets: optional (N, 2) candidate table points (e.g. the parts' positions): the target is one
                of them, preferring those the hand can reach; None draws a point on the table's +x half.
            eye: optional (3,) camera position; the hand then goes on the camera's line of sight to the
                target, so it hides the target in the image.
            start_s: (min, max) seconds before the reach starts.
            reach_s: (min, max) seconds the reach takes.
            pause_s: (min, max) seconds the hand stays at the target.
            withdraw_s: (min, max) seconds the withdrawal takes.
            hand_height: (min, max) metres of the hand over the table at the target.
        """
        if not isinstance(rng, np.random.Generator):
            raise SimInputError("ReachSchedule.sample needs rng, a numpy.random.Generator")
        half = np.asarray(table_size, dtype=float) / 2
        if half.shape != (2,) or np.any(half <= 0):
            raise SimInputError(f"table_size must be (x, y) > 0 in metres, got {table_size}")
        times = [rng.uniform(*r) for r in (start_s, reach_s, pause_s, withdraw_s)]
        height = rng.uniform(*hand_height)
        if targets is None or len(targets) == 0:
            target = np.array([rng.uniform(0.0, 0.8 * half[0]), rng.uniform(-0.8 * half[1], 0.8 * half[1])])
        else:
            candidates = np.asarray(targets, dtype=float).reshape(-1, 2)
            reachable = candidates[candidates[:, 0] > -0.2 * half[0]]
            pool = reachable if len(reachable) else candidates
            target = pool[rng.integers(len(pool))]
        hand = target.copy()
        if eye is not None:
            eye = np.asarray(eye, dtype=float)
            f = height / max(eye[2] - table_top, height + 1e-3)
            hand = target + f * (eye[:2] - target)
        shoulder_y = float(np.clip(hand[1] + 0.12 + rng.uniform(-0.05, 0.05), -half[1], half[1]))
        return cls(*times, target_xy=tuple(target), hand_xy=tuple(hand), hand_height=float(height),
                   shoulder_y=shoulder_y, edge_x=float(half[0]), table_top=float(table_top))


def occlusion_at(schedule: ReachSchedule, t: float) -> float:
    """How far the reach has gone at time ``t`` (s), in [0, 1]: 0 at rest, 1 during the pause (minimum-jerk)."""
    s = schedule
    if t <= s.start_s or t >= s.end_s:
        return 0.0
    if t < s.peak_s[0]:
        return minimum_jerk((t - s.start_s) / s.reach_s)
    if t <= s.peak_s[1]:
        return 1.0
    return 1.0 - minimum_jerk((t - s.peak_s[1]) / s.withdraw_s)


def _unit(v) -> np.ndarray:
    return np.asarray(v, dtype=float) / np.linalg.norm(v)


def _capsule(a, b) -> np.ndarray:
    """Pose (4, 4) of a capsule from point a to b: origin at the midpoint, z along a -> b."""
    z = _unit(np.asarray(b, dtype=float) - a)
    ref = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = _unit(cross(ref, z))
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, cross(z, x), z])
    T[:3, 3] = (np.asarray(a, dtype=float) + b) / 2
    return T


def _elbow(shoulder, wrist):
    """Two-link IK: (elbow, wrist), the wrist pulled in when out of reach; the elbow points down and out (+y)."""
    d_vec = wrist - shoulder
    d = float(np.linalg.norm(d_vec))
    d_clamped = min(max(d, abs(UPPER_ARM - FOREARM) + 1e-6), UPPER_ARM + FOREARM - 1e-6)
    u = d_vec / d
    wrist = shoulder + d_clamped * u
    a = (UPPER_ARM**2 - FOREARM**2 + d_clamped**2) / (2 * d_clamped)
    h = math.sqrt(max(UPPER_ARM**2 - a * a, 0.0))
    pole = np.array([0.0, 0.5, -1.0])
    n = pole - (pole @ u) * u
    n = _unit(n) if np.linalg.norm(n) > 1e-9 else _unit(np.cross(u, [1.0, 0.0, 0.0]))
    return shoulder + a * u + h * n, wrist


def occluder_pose(schedule: ReachSchedule, t: float) -> dict[str, np.ndarray]:
    """Poses (4, 4, world frame, metres) of the occluder's mocap bodies at time ``t`` (s).

    Returns:
        {``"human/torso"``, ``"human/upper_arm"``, ``"human/forearm"``, ``"human/hand"``: T_world_body};
        each body's z axis runs along its capsule, origin at the capsule's centre.
    """
    s = schedule
    k = occlusion_at(s, t)
    origin = np.array([s.edge_x, s.shoulder_y, s.table_top])
    shoulder = origin + (1 - k) * _SHOULDER_REST + k * SHOULDER_REACH
    hand_rest = origin + _HAND_REST
    hand_peak = np.array([*s.hand_xy, s.table_top + s.hand_height])
    hand = (1 - k) * hand_rest + k * hand_peak + np.array([0.0, 0.0, _LIFT * math.sin(math.pi * k)])
    # The hand points from the shoulder's side towards the target, level at the peak, down at rest.
    reach_dir = np.array([*(hand_peak[:2] - shoulder[:2]), 0.0])
    reach_dir = _unit(reach_dir) if np.linalg.norm(reach_dir) > 1e-9 else np.array([-1.0, 0.0, 0.0])
    hand_dir = _unit(k * reach_dir + (1 - k) * np.array([0.0, 0.0, -1.0]) + np.array([0.0, 0.0, -0.05]))
    elbow, wrist = _elbow(shoulder, hand - hand_dir * HAND / 2)
    tips = wrist + hand_dir * HAND
    hip = origin + np.array([0.35, _TORSO_SIDE, -0.10])
    neck = hip + _unit(shoulder + np.array([0.0, _TORSO_SIDE, 0.0]) - hip) * TORSO_LENGTH
    return {
        PREFIX + "torso": _capsule(hip, neck),
        PREFIX + "upper_arm": _capsule(shoulder, elbow),
        PREFIX + "forearm": _capsule(elbow, wrist),
        PREFIX + "hand": _capsule(wrist, tips),
    }


def segment_half_lengths() -> dict[str, float]:
    """Half the axis length (m) of each capsule, keyed like :func:`occluder_pose` (MuJoCo's capsule size[1])."""
    return {PREFIX + "torso": TORSO_LENGTH / 2, PREFIX + "upper_arm": UPPER_ARM / 2,
            PREFIX + "forearm": FOREARM / 2, PREFIX + "hand": HAND / 2}
