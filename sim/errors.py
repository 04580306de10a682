"""The sim's exception hierarchy: everything the sim raises on purpose derives from :class:`SimError`.

``SimError`` is a :class:`psorr.errors.PsorrError`, so one ``except PsorrError`` catches the recognizer's
errors and the cell's alike (``psorr-sim`` prints either as one line). An error about bad input is also
psorr's :class:`~psorr.errors.InvalidInputError` (and so a ``ValueError``), an error about a bad task
file is also its :class:`~psorr.errors.CloudFileError`, and one about the catalog's grasps also its
:class:`~psorr.synthetic.catalog.CatalogError`, so code written against psorr's hierarchy keeps catching
them. Every message names the cause and the fix, or the valid choices.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from psorr.errors import CloudFileError, InvalidInputError, PsorrError
from psorr.synthetic.catalog import CatalogError

if TYPE_CHECKING:
    from sim.control.ik import IKResult


class SimError(PsorrError):
    """Root of every error the sim raises on purpose; catch this to handle them all."""


class SimInputError(SimError, InvalidInputError):
    """An argument has the wrong type or value (an unknown part, a mode, a range); the message names the
    valid choices."""


class TaskFileError(SimError, CloudFileError):
    """A task file (``tasks/*.yaml``) is missing, unreadable or asks for something the cell cannot be;
    the message names the file, the problem and the fix."""


class UnreachableGoalError(SimError):
    """A process plan's goal cannot be reached in its cell: an object not on the table, a part sent where the
    cell cannot put it, a goal at odds with itself, or a person's actions that do not reach it. Raised
    before the robot moves; the message names the plan file and the reason."""


class GraspCatalogError(SimError, CatalogError):
    """The workpiece catalog's grasps cannot be read; the message names the file, the problem and the fix."""


class WorldBuildError(SimError):
    """The world cannot be assembled as configured; the message names the cause and the fix."""


class RenderBackendError(SimError):
    """No headless OpenGL backend works; the message names the backends tried and the fix."""


class UnreachableTargetError(SimError):
    """The IK did not bring the tool to the target pose; ``result`` holds its closest attempt."""

    def __init__(self, message: str, result: IKResult):
        super().__init__(message)
        self.result = result


class WorkspaceBlockedError(SimError):
    """Someone kept reaching over the table for longer than a protective stop may last
    (:data:`sim.control.cell.MAX_STOP_S`)."""


class RecordingError(SimError):
    """The recording cannot be written; the message names the path and the fix."""


class ResetNeededError(SimError):
    """The env was stepped or rendered before :meth:`sim.env.PickPlaceEnv.reset`."""


class PartMeshError(SimError, CloudFileError):
    """A mesh a task names cannot become a part of the cell (unreadable, not closed, too small for the sensor,
    too wide for the gripper from every side); the message names the file, the reason and the fix."""


class CollisionHullError(SimError, CloudFileError):
    """A mesh's collision hulls cannot be derived: CoACD is not installed, failed, or took too long
    (:func:`sim.parts.collision.collision_hulls`); the message names the mesh file, the reason and the fix."""
