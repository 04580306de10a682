"""The person at the table: reaches over it now and then, choosing where, and pulls back from the robot.

:mod:`sim.people.occluder` gives the geometry of one reach (:class:`~sim.people.occluder.ReachSchedule`, the
capsule poses); :class:`ReachingHuman` strings reaches together over an episode and reacts to
where the robot arm is. Frames and units as in :mod:`sim.people.occluder` (world frame, metres, seconds).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sim.errors import SimInputError
from sim.people.occluder import SHOULDER_REACH, ReachSchedule, minimum_jerk, occluder_pose, occlusion_at


class ReachingHuman:
    """A person who reaches over the table now and then, and does not reach into the robot.

    Each reach starts ``gap_s`` after the last one ended (the first within ``first_s``). When one
    is due the person picks where to reach: one of ``targets`` (N, 2), or a random point on the
    table, whose arm at the peak stays ``keep_away`` from the robot arm's footprint (the polyline
    from its base to its tool, seen from above); if there is none, the reach is put off by a
    second. So the person reacts to the robot, and the reaches depend on where it is, but a
    seed still gives the same episode: the robot's motion is deterministic too.

    Args:
        rng: the person's only randomness.
        table_size: as for :meth:`ReachSchedule.sample`.
        table_top: as for :meth:`ReachSchedule.sample`.
        targets: as for :meth:`ReachSchedule.sample`.
        eye: as for :meth:`ReachSchedule.sample`.
        first_s: (min, max) seconds before the first reach.
        gap_s: (min, max) seconds between reaches.
        keep_away: metres between the hand at its peak and the arm's footprint.
    """

    def __init__(self, rng: np.random.Generator, table_size, table_top: float, targets=None, eye=None,
                 first_s: tuple[float, float] = (0.0, 3.0), gap_s: tuple[float, float] = (2.0, 8.0),
                 keep_away: float = 0.25):
        if not isinstance(rng, np.random.Generator):
            raise SimInputError("ReachingHuman needs rng, a numpy.random.Generator")
        self.rng, self.table_size, self.table_top = rng, table_size, float(table_top)
        self.targets = np.empty((0, 2)) if targets is None else np.asarray(targets, dtype=float).reshape(-1, 2)
        self.eye, self.gap_s, self.keep_away = eye, gap_s, float(keep_away)
        self.reaches: list[ReachSchedule] = []
        # A reach that never starts: the pose at rest, by the table's edge.
        self._rest = ReachSchedule.sample(rng, table_size, table_top, self.targets, eye, start_s=(1e12, 1e12))
        self._next = float(rng.uniform(*first_s))
        self._resting: tuple[ReachSchedule, dict] | None = None

    @property
    def current(self) -> ReachSchedule:
        """The reach under way, or the last one (a resting schedule before the first)."""
        return self.reaches[-1] if self.reaches else self._rest

    def update(self, t: float, robot_xy) -> dict[str, np.ndarray]:
        """Advance to time ``t`` (s) with the robot arm's footprint at ``robot_xy`` ((N, 2) m, a polyline
        from its base through its links to the tool, seen from above); return the capsule poses as
        :func:`occluder_pose` does.

        A reach whose arm the robot's footprint comes within ``keep_away`` of is abandoned: the
        person pulls back from where the hand is.
        """
        robot = np.asarray(robot_xy, dtype=float).reshape(-1, 2)
        if t >= self._next and (not self.reaches or t >= self.reaches[-1].end_s):
            candidates = np.vstack([self.targets, self._table_points(4)])
            self.rng.shuffle(candidates)
            for target in candidates:
                reach = ReachSchedule.sample(self.rng, self.table_size, self.table_top, [target], self.eye,
                                             start_s=(t, t))
                if self._clearance(reach, robot) >= self.keep_away:
                    self.reaches.append(reach)
                    self._next = reach.end_s + float(self.rng.uniform(*self.gap_s))
                    break
            else:
                self._next = t + 1.0
        elif self.reaches and self.reaches[-1].start_s < t < self.reaches[-1].peak_s[1]:
            if self._clearance(self.reaches[-1], robot) < self.keep_away:
                self.reaches[-1] = _withdrawn_at(self.reaches[-1], t)
                self._next = self.reaches[-1].end_s + float(self.rng.uniform(*self.gap_s))
        reach = self.current
        k = occlusion_at(reach, t)
        if k == 0.0 and self._resting is not None and self._resting[0] is reach:
            return self._resting[1]  # standing still at rest: most of the time, and the pose is dearer than a step
        poses = occluder_pose(reach, t)
        self._resting = (reach, poses) if k == 0.0 else None
        return poses

    def _clearance(self, reach: ReachSchedule, robot_xy: np.ndarray) -> float:
        """Least distance, seen from above, between the person's arm at the reach's peak and the robot's."""
        shoulder = np.array([reach.edge_x + SHOULDER_REACH[0], reach.shoulder_y])
        hand = np.asarray(reach.hand_xy)
        if len(robot_xy) == 1:
            robot_xy = np.vstack([robot_xy, robot_xy])
        return min(_segments_distance(shoulder, hand, a, b) for a, b in zip(robot_xy[:-1], robot_xy[1:]))

    def _table_points(self, n: int) -> np.ndarray:
        half = np.asarray(self.table_size, dtype=float) / 2
        return self.rng.uniform(-0.8, 0.8, size=(n, 2)) * half


def _segments_distance(a0, a1, b0, b1, samples: int = 32) -> float:
    """Distance between 2-D segments a0-a1 and b0-b1 (sampled along the first; exact enough at 32)."""
    b0, b1 = np.asarray(b0, dtype=float), np.asarray(b1, dtype=float)
    pts = np.linspace(0.0, 1.0, samples)[:, None] * (np.asarray(a1) - a0) + a0
    ab = b1 - b0
    s = np.clip((pts - b0) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return float(np.min(np.linalg.norm(pts - (b0 + s[:, None] * ab), axis=1)))


def _withdrawn_at(reach: ReachSchedule, t: float) -> ReachSchedule:
    """``reach`` cut short: from time ``t`` the arm withdraws from where it is, taking ``withdraw_s``."""
    k = occlusion_at(reach, t)
    # The withdrawal's progress tau where 1 - minimum_jerk(tau) = k; minimum_jerk is monotonic.
    grid = np.linspace(0.0, 1.0, 1001)
    tau = float(np.interp(1.0 - k, [minimum_jerk(g) for g in grid], grid))
    peak_end = t - tau * reach.withdraw_s
    return replace(reach, start_s=max(0.0, peak_end - reach.reach_s), pause_s=0.0,
                   reach_s=max(1e-3, peak_end - max(0.0, peak_end - reach.reach_s)))
