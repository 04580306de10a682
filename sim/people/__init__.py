"""The person at the table: the geometry and timing of one reach over it (:mod:`~sim.people.occluder`,
mocap capsules on a minimum-jerk schedule) and the person who strings reaches together and keeps clear
of the robot (:mod:`~sim.people.human`)."""

from sim.people.human import ReachingHuman
from sim.people.occluder import ReachSchedule, occluder_pose, occlusion_at

__all__ = ["ReachSchedule", "ReachingHuman", "occluder_pose", "occlusion_at"]
