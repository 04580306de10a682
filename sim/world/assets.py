"""Where the sim finds the files it ships with: one constant per file or folder, each computed on its own
line so that changing how one is found (a package resource instead of a checkout path) touches that line only.

The paths are the checkout's: this file is ``sim/world/assets.py``, so the repository root is
``parents[2]``.
"""

from __future__ import annotations

from pathlib import Path

ARM_XML = Path(__file__).resolve().parents[2] / "assets" / "robot" / "arm.xml"
"""The arm's MJCF (metres, radians), read by :func:`sim.world.robot.load_arm_spec`."""

COLLISION_DIR = Path(__file__).resolve().parents[2] / "assets" / "workpieces" / "collision"
"""CoACD collision parts and their index.json, written by assets/workpieces/build_collision.py."""

REPO_ROOT = Path(__file__).resolve().parents[2]
"""The checkout: a relative task path the working directory does not hold is looked up from here
(``tasks/demo.yaml``, the env's default task)."""
