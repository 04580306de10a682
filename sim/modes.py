"""The sim's closed sets of modes, as ``StrEnum`` s.

A member compares equal to its string (``PoseSource.ORACLE == "oracle"``), so callers may keep passing
plain strings: each mode is converted where it enters the sim (:func:`parse_mode`), and an unknown one is
refused naming the valid choices. Command-line choices are read from the enums. This module loads no
MuJoCo, so the command line builds its parser without it.
"""

from __future__ import annotations

from enum import StrEnum
from typing import TypeVar

from sim.errors import SimInputError

Mode = TypeVar("Mode", bound=StrEnum)


class PoseSource(StrEnum):
    """Where the robot's pose estimates come from."""

    RECOGNIZED = "recognized"
    """PSORR on the Kinect's cloud: the robot sees the cell as a real one would."""
    ORACLE = "oracle"
    """The simulator's true poses: what the cell does when recognition is perfect."""


def choices(mode: type[StrEnum]) -> list[str]:
    """The valid strings of ``mode``, in definition order (for messages and command-line choices)."""
    return [member.value for member in mode]


def parse_mode(mode: type[Mode], value, what: str) -> Mode:
    """``value`` (a member or its string) as a member of ``mode``; SimInputError naming ``what`` and the
    valid choices otherwise."""
    try:
        return mode(value)
    except ValueError:
        raise SimInputError(f"{what} must be one of {choices(mode)}, got {value!r}") from None
