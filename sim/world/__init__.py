"""The robot cell as a scene: what it is built from (:mod:`~sim.world.config`, task files in
:mod:`~sim.world.tasks`), the arm's MJCF and names (:mod:`~sim.world.robot`), where the parts and
fixtures go (:mod:`~sim.world.layout`), the assembly with ``mujoco.MjSpec`` (:mod:`~sim.world.assembly`),
the handle to the built cell (:mod:`~sim.world.built`) and the files the sim ships with
(:mod:`~sim.world.assets`)."""

from sim.world.assembly import build_world
from sim.world.built import HOME_KEY, World
from sim.world.config import WorldConfig
from sim.world.robot import ArmConfig
from sim.world.tasks import Task, load_task

__all__ = ["HOME_KEY", "ArmConfig", "Task", "World", "WorldConfig", "build_world", "load_task"]
