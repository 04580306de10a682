"""Why a pick failed, from its :class:`sim.skills.judging.PickResult` (for benchmarks/episodes.py's table).

The reasons, first match wins:

- out of time: the episode ran out of simulated time, or the person kept the workspace blocked;
- not recognised: the part was never picked, since no look returned it;
- unreachable: no grasp of it could be planned (the IK, the table, or no grasp from above);
- collision: the arm would have touched something, or a move was aborted mid-pick;
- wrong pose: the estimate it was picked from was off by more than ``WRONG_POSE_MM`` or ``WRONG_POSE_DEG``;
- grasp slipped: the gripper closed on it but it did not come up, or was dropped on the way;
- not placed: it was carried to its place but did not end seated there (or at rest in the tote).
"""

from __future__ import annotations

# Past about 4 mm and 3 deg of pose error the catalog's placing falls under 90% (results/grasp_tolerance.md).
WRONG_POSE_MM = 5.0
WRONG_POSE_DEG = 5.0
REASONS = ("out of time", "not recognised", "unreachable", "collision", "wrong pose", "grasp slipped", "not placed")
_OUT_OF_TIME = ("not picked within", "the episode ended", "the workspace stayed occupied")


def failure_reason(pick) -> str | None:
    """The reason ``pick`` failed (one of REASONS), or None when it was grasped and placed."""
    if pick.grasped and pick.placed:
        return None
    if not pick.grasp_name and pick.note.startswith(_OUT_OF_TIME):
        return "out of time"
    if not pick.grasp_name and not pick.note.startswith(("no reachable grasp", "estimate not resting")):
        return "not recognised"
    if pick.note.startswith(("no reachable grasp", "estimate not resting")):
        return "unreachable"
    if "would touch" in pick.note or "aborted mid-pick" in pick.note:
        return "collision"
    if pick.pose_error_mm > WRONG_POSE_MM or pick.rot_error_deg > WRONG_POSE_DEG:
        return "wrong pose"
    if not pick.grasped:
        return "grasp slipped"
    return "not placed"


def failure_counts(results) -> dict[str, int]:
    """Reason -> how many of the picks of ``results`` (EpisodeResults) failed for it, every reason listed."""
    reasons = [failure_reason(p) for r in results for p in r.picks]
    return {reason: reasons.count(reason) for reason in REASONS}


def failure_table(results_by_mode: dict) -> list[str]:
    """Markdown lines: per mode, how many picks failed for each reason."""
    lines = ["| mode | failed picks | " + " | ".join(REASONS) + " |", "|---|---|" + "---|" * len(REASONS)]
    for mode, results in results_by_mode.items():
        counts = failure_counts(results)
        lines.append(f"| {mode} | {sum(counts.values())} | " + " | ".join(str(counts[x]) for x in REASONS) + " |")
    return lines
