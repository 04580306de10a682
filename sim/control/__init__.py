"""Moving the arm: differential IK of the tool site with mink (:mod:`~sim.control.ik`), and the cell that
steps the physics through ramped joint moves, tool paths and the gripper while the workspace monitor
may stop it (:mod:`~sim.control.cell`)."""

from sim.control.cell import ArmCell, WorkspaceMonitor
from sim.control.ik import ArmIK, IKResult, T_world_site
from sim.control.recorder_hooks import Recorder

__all__ = ["ArmCell", "ArmIK", "IKResult", "Recorder", "T_world_site", "WorkspaceMonitor"]
