"""The exception hierarchy: everything psorr raises on purpose derives from PsorrError."""

from __future__ import annotations


class PsorrError(Exception):
    """Root of every error psorr raises on purpose; catch this to handle them all."""


class InvalidInputError(PsorrError, ValueError):
    """An argument has the wrong shape, type or value. The message names the fix."""


class TooSparseError(InvalidInputError):
    """A cloud holds too few points, or too few voxels, to decompose into primitives."""


class CloudFileError(PsorrError):
    """A cloud or mesh file is missing, empty, all-NaN, malformed or of an unknown format."""

    def __init__(self, path, problem: str, fix: str = ""):
        self.path = str(path)
        message = f"{self.path}: {problem}"
        if fix:
            message += f" ({fix})"
        super().__init__(message)


class AssetError(CloudFileError):
    """A file of psorr's package data (the workpiece catalog, a mesh, a collision mesh, the robot MJCF) is missing."""


class MissingExtraError(PsorrError, ImportError):
    """An optional feature's library is not installed. The message names the extra that installs it."""


class ViewerError(PsorrError):
    """The Rerun viewer a recording streams to cannot be started or reached. The message names the fix."""
