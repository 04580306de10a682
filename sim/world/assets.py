"""Where the sim finds the files it ships with: psorr's package data (:mod:`psorr.assets`), one constant
per file or folder. In a checkout they are the repository's ``assets/`` folder; installed, the package's."""

from __future__ import annotations

from psorr.assets import asset_path

ARM_XML = asset_path("robot", "arm.xml")
"""The arm's MJCF (metres, radians), read by :func:`sim.world.robot.load_arm_spec`."""

COLLISION_DIR = asset_path("workpieces", "collision")
"""CoACD collision parts and their index.json, written by assets/workpieces/build_collision.py."""
