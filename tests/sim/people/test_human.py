"""The reaching person (sim/people/human.py): keeps clear of the arm, pulls back smoothly. Headless."""

import numpy as np
import pytest

from sim.people.human import ReachingHuman
from sim.people.occluder import ReachSchedule, occlusion_at


def test_the_person_does_not_reach_where_the_arm_is():
    rng = np.random.default_rng(3)
    human = ReachingHuman(rng, (0.9, 1.0), 0.75, targets=[(0.1, 0.0)], keep_away=0.25)
    base, tool = np.array([-0.35, 0.0]), np.array([0.1, 0.0])  # the arm lies over the only target
    for t in np.arange(0.0, 20.0, 0.1):
        human.update(t, [base, tool])
    # Random table points remain possible targets, but never one within reach of the arm's footprint.
    for reach in human.reaches:
        assert human._clearance(reach, np.array([base, tool])) >= 0.25


def test_the_person_pulls_back_when_the_arm_comes_near_and_the_motion_is_continuous():
    rng = np.random.default_rng(0)
    human = ReachingHuman(rng, (0.9, 1.0), 0.75, targets=[(0.2, 0.3)], first_s=(0.0, 0.0))
    base, far_tool = np.array([-0.35, 0.0]), np.array([-0.3, -0.4])
    human.update(0.0, [base, far_tool])
    reach = human.reaches[-1]
    t = reach.start_s + 0.6 * reach.reach_s
    before = human.update(t, [base, far_tool])
    k = occlusion_at(human.current, t)
    after = human.update(t + 1e-6, [base, np.asarray(reach.hand_xy)])  # the arm arrives where the hand goes
    assert human.current.end_s < reach.end_s  # cut short
    assert occlusion_at(human.current, t + 1e-6) == pytest.approx(k, abs=1e-3)
    for name in before:
        assert np.allclose(before[name][:3, 3], after[name][:3, 3], atol=2e-3)
    assert occlusion_at(human.current, human.current.end_s + 1e-3) == 0.0


def test_reach_schedules_are_still_checked():
    with pytest.raises(Exception, match="reach_s"):
        ReachSchedule(0.0, 0.0, 0.0, 1.0, (0, 0), (0, 0), 0.2, 0.0, 0.45, 0.75)
