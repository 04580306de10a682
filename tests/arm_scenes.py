"""The arm on its own and attached into a small scene, shared by the arm's tests (tests/sim/world/test_robot.py)
and the IK's (tests/sim/control/test_ik.py)."""

import warnings

import mujoco
import numpy as np

from sim.control.ik import T_world_site
from sim.world.robot import ArmConfig, apply_arm_options, load_arm_spec

CFG = ArmConfig()
TOOL_DOWN = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # home's tool axes


def tool_pose(model, q, cfg=CFG):
    """The tool site's pose (4, 4) at joints ``q`` (nq,), by forward kinematics."""
    data = mujoco.MjData(model)
    data.qpos[:] = q
    mujoco.mj_kinematics(model, data)
    return T_world_site(model, data, cfg.tool_site)


def arm_scene(part_half_size=None):
    """A world with a floor, its own 'visual' class, a free part, and the arm attached as 'arm/'."""
    world = mujoco.MjSpec()
    apply_arm_options(world)
    world.add_default("visual", world.default)  # a clashing class name the prefix must keep apart
    world.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
    if part_half_size is not None:
        part = world.worldbody.add_body(name="part", pos=[0.5, 0.0, part_half_size[2]])
        part.add_freejoint(name="part_free")
        part.add_geom(name="part", type=mujoco.mjtGeom.mjGEOM_BOX, size=part_half_size, mass=0.3)
    yaw = 0.4
    frame = world.worldbody.add_frame(pos=[0.1, -0.2, 0.0], quat=[np.cos(yaw / 2), 0, 0, np.sin(yaw / 2)])
    world.attach(load_arm_spec(), prefix="arm/", frame=frame)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # attach conflicts (options, names) surface as warnings
        return world.compile()
