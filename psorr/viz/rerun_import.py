"""Rerun (``rerun-sdk``) is optional: imported only when a recording is asked for; and the recording stream
that both the recognizer's and the simulator's recorders write to."""

from __future__ import annotations

from psorr.errors import MissingExtraError, ViewerError

VIZ_EXTRA = "pip install 'psorr[viz]'"
_NO_VIEWER_FIX = f"install the viewer ({VIZ_EXTRA} puts `rerun` on the PATH), or record into a file: --rerun OUT.rrd"


def import_rerun():
    """The ``rerun`` module, or a MissingExtraError naming the extra that installs it."""
    try:
        import rerun
    except ImportError:
        raise MissingExtraError(f"recording for the Rerun viewer needs rerun-sdk, which is not installed: "
                                f"{VIZ_EXTRA}") from None
    return rerun


def _first_line(exc: Exception) -> str:
    return str(exc).splitlines()[0].rstrip(".") if str(exc) else type(exc).__name__


class RerunStream:
    """A ``rerun.RecordingStream`` to log into: a new one writing ``path`` (an ``.rrd``), or streaming to a
    viewer spawned here when ``path`` is None; or ``recording``, one the caller made and finishes. Use as a
    context manager, or call :meth:`close`.

    A new stream has no wall-clock or tick columns: the recorder's own timeline orders it, and the log times
    could only be read back with pandas installed.
    """

    def __init__(self, application_id: str, path=None, recording=None):
        self.rr = import_rerun()
        self._own = recording is None
        if recording is None:
            recording = self.rr.RecordingStream(application_id)
            recording.set_log_time_enabled(False)
            recording.set_log_tick_enabled(False)
            if path is not None:
                recording.save(str(path))
            else:
                self._spawn(recording)
        self.recording = recording

    @staticmethod
    def _spawn(recording) -> None:
        try:
            recording.spawn()
        except RuntimeError as exc:  # no `rerun` on the PATH
            raise ViewerError(f"cannot start the Rerun viewer: {_first_line(exc)}; {_NO_VIEWER_FIX}") from None

    def close(self) -> None:
        """Flush what is recorded to its file or viewer, and finish the file (a recording passed in is the
        caller's to finish)."""
        try:
            self.recording.flush()
        except RuntimeError as exc:  # the spawned viewer never answered, or went away
            raise ViewerError(f"the Rerun viewer did not take the recording: {_first_line(exc)}; "
                              f"{_NO_VIEWER_FIX}") from None
        finally:
            if self._own:
                self.recording.disconnect()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()
