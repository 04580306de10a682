"""Rerun (``rerun-sdk``) is optional: imported only when a recording is asked for."""

from __future__ import annotations

from psorr.errors import MissingExtraError

VIZ_EXTRA = "pip install 'psorr[viz]'"


def import_rerun():
    """The ``rerun`` module, or a MissingExtraError naming the extra that installs it."""
    try:
        import rerun
    except ImportError:
        raise MissingExtraError(f"recording for the Rerun viewer needs rerun-sdk, which is not installed: "
                                f"{VIZ_EXTRA}") from None
    return rerun
