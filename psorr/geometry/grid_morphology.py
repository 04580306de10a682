"""Binary morphology on 2-D grids with the 4-connected cross, as shifted boolean arrays.

These equal scipy.ndimage's binary_dilation, binary_erosion, binary_closing and binary_opening with their
default structure (the cross) and border (outside the grid is empty), cell for cell. scipy walks the
structure per cell in C; on the resting-pose search's table grid (some 300 x 350 cells, a closing of two
iterations and an opening a scene) that took 8.6 ms, the shifts 0.5 ms.
"""

from __future__ import annotations

import numpy as np


def dilate(mask: np.ndarray, iterations: int = 1) -> np.ndarray:
    """(H, W) bool: the cells of ``mask`` (H, W) and their four neighbours, ``iterations`` times."""
    out = np.asarray(mask, dtype=bool)
    for _ in range(iterations):
        grown = out.copy()
        grown[1:] |= out[:-1]
        grown[:-1] |= out[1:]
        grown[:, 1:] |= out[:, :-1]
        grown[:, :-1] |= out[:, 1:]
        out = grown
    return out


def erode(mask: np.ndarray, iterations: int = 1) -> np.ndarray:
    """(H, W) bool: the cells of ``mask`` (H, W) whose four neighbours are all in it, ``iterations`` times;
    a border cell has a neighbour outside the grid, which is empty."""
    out = np.asarray(mask, dtype=bool)
    for _ in range(iterations):
        kept = out.copy()
        kept[1:] &= out[:-1]
        kept[:-1] &= out[1:]
        kept[:, 1:] &= out[:, :-1]
        kept[:, :-1] &= out[:, 1:]
        kept[0], kept[-1], kept[:, 0], kept[:, -1] = False, False, False, False
        out = kept
    return out


def closing(mask: np.ndarray, iterations: int = 1) -> np.ndarray:
    """(H, W) bool: ``mask`` dilated, then eroded, ``iterations`` times each: gaps that narrow filled."""
    return erode(dilate(mask, iterations), iterations)


def opening(mask: np.ndarray, iterations: int = 1) -> np.ndarray:
    """(H, W) bool: ``mask`` eroded, then dilated, ``iterations`` times each: specks that small removed."""
    return dilate(erode(mask, iterations), iterations)
