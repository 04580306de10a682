"""The robot arm of the cell: where its MJCF lives and the names a controller needs.

The arm is a 6-DoF arm with the UR5e's standard-DH kinematics and a 2-finger parallel gripper,
written in ``assets/robot/arm.xml`` (read the comment at its top for frames and units). A scene
loads it with :func:`load_arm_spec` and attaches it into its own ``mujoco.MjSpec``; attaching
with a prefix renames everything, so use :meth:`ArmConfig.with_prefix` for the names then.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import mujoco

from sim.world.assets import ARM_XML

ARM_OPTIONS = ("timestep", "integrator", "cone", "impratio")
"""Simulation options the arm is tuned for (stable gains, pads that do not let a part creep)."""


def load_arm_spec() -> mujoco.MjSpec:
    """Parse the arm's MJCF into a fresh, editable spec (one per call, so callers may mutate it).

    ``spec.attach`` keeps the parent's options and warns where the arm's differ, so a scene
    should call :func:`apply_arm_options` on its own spec first.
    """
    return mujoco.MjSpec.from_file(str(ARM_XML))


def apply_arm_options(spec: mujoco.MjSpec) -> None:
    """Set the ``ARM_OPTIONS`` of a scene's spec to the arm's: 2 ms implicitfast, elliptic cones, impratio 10."""
    arm = load_arm_spec()
    for name in ARM_OPTIONS:
        setattr(spec.option, name, getattr(arm.option, name))


@dataclass(frozen=True)
class ArmConfig:
    """Names and gripper commands of the arm in ``ARM_XML``; defaults match the file unprefixed.

    Attributes:
        arm_joints: The 6 arm joints, base to wrist (hinges, rad).
        arm_actuators: Their position actuators, same order (command = joint angle, rad).
        finger_joints: The 2 finger slides (m, each pad's distance from the tool site).
        gripper_actuator: The one actuator of both fingers; its command is the pad opening (m).
        tool_site: The grasp point midway between the pads; z = approach, x = closing direction.
        pad_geoms: The two high-friction finger pad geoms.
        collision_geoms: Every collision geom of the arm and gripper (for collision pairs).
        base_body: The body fixed at the arm's mounting point.
        home_key: The keyframe with the tool pointing down above the table.
        gripper_open: Command for fully open (m of opening).
        gripper_closed: Command for fully closed (m).
        max_opening: Largest opening between the pads (m).
    """

    arm_joints: tuple[str, ...] = (
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    )
    arm_actuators: tuple[str, ...] = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
    finger_joints: tuple[str, ...] = ("left_finger_joint", "right_finger_joint")
    gripper_actuator: str = "gripper"
    tool_site: str = "tool"
    pad_geoms: tuple[str, ...] = ("left_pad", "right_pad")
    collision_geoms: tuple[str, ...] = (
        "base_collision",
        "shoulder_collision",
        "upper_arm_collision",
        "elbow_collision",
        "forearm_collision",
        "wrist_1_collision",
        "wrist_2_collision",
        "wrist_3_collision",
        "gripper_collision",
        "left_finger_collision",
        "right_finger_collision",
        "left_pad",
        "right_pad",
    )
    base_body: str = "base"
    home_key: str = "home"
    gripper_open: float = 0.08
    gripper_closed: float = 0.0
    max_opening: float = 0.08

    def with_prefix(self, prefix: str) -> ArmConfig:
        """The same config with every name prefixed, as after ``spec.attach(arm, prefix=prefix)``."""
        renamed = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, str):
                renamed[f.name] = prefix + value
            elif isinstance(value, tuple):
                renamed[f.name] = tuple(prefix + v for v in value)
        return replace(self, **renamed)
