"""Truncated distance fields of point sets on a regular grid, in two or three dimensions.

A field answers "how far is this point from the set?" for millions of query points in one gather,
which is what a search over many poses of one shape needs. Distances beyond the truncation, and
queries outside the grid, read as the truncation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage


@dataclass(frozen=True, eq=False)
class DistanceField:
    """Distances (the points' unit) from each grid cell's corner region to the nearest point of a set.

    Attributes:
        low: (D,) the grid's first corner; cell: the cells' edge;
        distances: (n_1, ..., n_D) float32, each at most ``truncation``.
    """

    low: np.ndarray
    cell: float
    distances: np.ndarray
    truncation: float

    @classmethod
    def of_points(cls, points: np.ndarray, cell: float, truncation: float) -> DistanceField:
        """The field of ``points`` (N, D), on a grid of ``cell`` reaching ``truncation`` past them.
        A cell holding a point reads 0; the others, the distance between cell centres."""
        points = np.asarray(points, dtype=float)
        low = points.min(axis=0) - truncation - cell
        shape = np.floor((points.max(axis=0) + truncation + cell - low) / cell).astype(np.int64) + 1
        empty = np.ones(tuple(shape), dtype=bool)
        empty[tuple(np.floor((points - low) / cell).astype(np.int64).T)] = False
        distances = np.minimum(ndimage.distance_transform_edt(empty) * cell, truncation)
        return cls(low, float(cell), distances.astype(np.float32), float(truncation))

    def __call__(self, points: np.ndarray) -> np.ndarray:
        """(...) distances of the query ``points`` (..., D)."""
        shape = self.distances.shape
        # The grid reaches a truncation and a cell past the points, so its border cells read the
        # truncation: a query outside, clipped onto the border, reads it too.
        index = np.clip(((points - self.low) / self.cell).astype(np.int64), 0, np.asarray(shape) - 1)
        flat = index @ np.asarray(self.distances.strides) // self.distances.itemsize
        return self.distances.reshape(-1)[flat]
