"""Colours: sRGB to CIELAB (D65), and the names of a small palette."""

from __future__ import annotations

import numpy as np

_WHITE = np.array([0.95047, 1.0, 1.08883])  # D65
_RGB_TO_XYZ = np.array([[0.4124564, 0.3575761, 0.1804375],
                        [0.2126729, 0.7151522, 0.0721750],
                        [0.0193339, 0.1191920, 0.9503041]])

# Names a user would give a workpiece's colour, at typical sRGB values.
PALETTE = {
    "red": (0.80, 0.10, 0.10), "orange": (0.95, 0.50, 0.10), "yellow": (0.95, 0.85, 0.15),
    "green": (0.15, 0.60, 0.20), "cyan": (0.10, 0.70, 0.80), "blue": (0.10, 0.25, 0.80),
    "purple": (0.50, 0.20, 0.60), "pink": (0.95, 0.55, 0.70), "brown": (0.50, 0.30, 0.15),
    "white": (0.92, 0.92, 0.92), "grey": (0.50, 0.50, 0.50), "black": (0.08, 0.08, 0.08),
}


def rgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    """(N, 3) sRGB in [0, 1] to (N, 3) CIELAB (L in [0, 100])."""
    rgb = np.asarray(rgb, dtype=np.float64)
    linear = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    xyz = linear @ _RGB_TO_XYZ.T / _WHITE
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.column_stack([116 * f[:, 1] - 16, 500 * (f[:, 0] - f[:, 1]), 200 * (f[:, 1] - f[:, 2])])


_PALETTE_NAMES = tuple(PALETTE)
_PALETTE_LAB = rgb_to_lab(np.array([PALETTE[n] for n in _PALETTE_NAMES]))


def colour_name(rgb) -> str:
    """The palette's name nearest (in CIELAB) to an sRGB colour (3,) in [0, 1]."""
    lab = rgb_to_lab(np.asarray(rgb, dtype=np.float64).reshape(1, 3))
    return _PALETTE_NAMES[int(np.argmin(np.linalg.norm(_PALETTE_LAB - lab, axis=1)))]
