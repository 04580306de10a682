"""What the robot does with the arm: look at the cell and recognise the parts
(:mod:`~sim.skills.perception`, with the recognizer and noise level of
:mod:`~sim.skills.perception_params`), choose a reachable one of the catalog's grasps
(:mod:`~sim.skills.grasps`, :mod:`~sim.skills.grasp_planning`),
pick and place a part (:mod:`~sim.skills.pick`) and judge it on the simulator's truth
(:mod:`~sim.skills.judging`), and tell a held part's near-symmetric twins apart
(:mod:`~sim.skills.in_hand`)."""

from sim.skills.grasp_planning import GraspPlan, plan_grasp
from sim.skills.grasps import Grasp, load_grasps
from sim.skills.in_hand import InHandLook, look_in_hand
from sim.skills.judging import PickResult
from sim.skills.perception import Estimate, Look, Perception
from sim.skills.perception_params import PerceptionParams
from sim.skills.pick import pick_and_place

__all__ = ["Estimate", "Grasp", "GraspPlan", "InHandLook", "Look", "Perception", "PerceptionParams", "PickResult",
           "load_grasps", "look_in_hand", "pick_and_place", "plan_grasp"]
