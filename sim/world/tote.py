"""The tote: a box on the table for parts that do not rest upright, with a slot for each part it takes.

A part lying any way is set down in the tote as it lay on the table, only turned about the vertical so
that its footprint's smallest rectangle lies along the tote's sides, in its own slot, so that parts put
there one after another do not land on each other. The slots form a grid as square as their count
allows; each column is as wide as its longest footprint, each row as deep as its widest, plus a margin,
so the tote's inside is sized by its parts rather than set by hand.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

SLOT_MARGIN = 0.015  # m around a footprint in its slot: a part set down may slide a little


@dataclass(frozen=True, eq=False)
class ToteLayout:
    """Where the tote's parts go, in the tote's frame (origin at the inside's centre on the table, metres).

    Attributes:
        half_inside: (2,) half the inside's x and y.
        slots: body name -> (2,) its slot's centre; a part lies there with its footprint's long side along x.
    """

    half_inside: np.ndarray
    slots: dict

    @classmethod
    def for_parts(cls, extents: dict[str, np.ndarray]) -> ToteLayout:
        """A layout for footprints of ``extents`` (body -> (2,) long and short side of its smallest rectangle)."""
        names = list(extents)
        cols = math.ceil(math.sqrt(len(names)))
        rows = math.ceil(len(names) / cols)
        width, depth = np.zeros(cols), np.zeros(rows)
        for k, name in enumerate(names):
            long, short = sorted(extents[name], reverse=True)
            width[k % cols] = max(width[k % cols], long + SLOT_MARGIN)
            depth[k // cols] = max(depth[k // cols], short + SLOT_MARGIN)
        half = np.array([width.sum(), depth.sum()]) / 2
        x0, y0 = np.cumsum(width) - width / 2 - half[0], np.cumsum(depth) - depth / 2 - half[1]
        slots = {n: np.array([x0[k % cols], y0[k // cols]]) for k, n in enumerate(names)}
        return cls(half, slots)

    def bounds(self) -> np.ndarray:
        """(2, 2) lo and hi corners of the inside, tote frame."""
        return np.array([-self.half_inside, self.half_inside])

    def holds(self, xy_in_tote: np.ndarray, margin: float = 0.0) -> bool:
        """Whether the tote-frame points (N, 2) all lie inside the tote (grown by ``margin``, m, on every side)."""
        return bool(np.all(np.abs(xy_in_tote) <= self.half_inside + margin))
