"""Judging where a part ended in the tote (sim.skills.judging)."""

import numpy as np

from sim.skills.judging import REST_TOL_MM, inside_walls
from sim.world.tote import ToteLayout

WALL = 0.006  # m, the default tote wall (sim.world.config.WorldConfig.tote_wall)
TOTE = ToteLayout(half_inside=np.array([0.1, 0.05]), slots={})


def _corners(x_max: float) -> np.ndarray:
    """A footprint's corners (4, 2) from x = 0 to ``x_max`` (m), well inside the tote in y."""
    return np.array([[0.0, -0.01], [x_max, -0.01], [x_max, 0.01], [0.0, 0.01]])


def test_a_part_well_inside_the_walls_is_inside():
    assert inside_walls(TOTE, _corners(0.08), WALL)


def test_a_part_pressing_into_the_inner_face_of_a_wall_is_inside():
    # At rest against the wall, the contact lets the hull reach a fraction of a millimetre into it.
    assert inside_walls(TOTE, _corners(0.1 + 0.0001), WALL)


def test_a_part_past_the_walls_inner_half_is_outside():
    assert not inside_walls(TOTE, _corners(0.1 + WALL / 2 + 0.0005), WALL)
    assert not inside_walls(TOTE, _corners(0.1 + WALL + 0.01), WALL)


def test_the_give_is_the_rest_tolerance_when_the_wall_is_thick():
    thick = 0.05
    assert inside_walls(TOTE, _corners(0.1 + REST_TOL_MM / 1e3 - 1e-4), thick)
    assert not inside_walls(TOTE, _corners(0.1 + REST_TOL_MM / 1e3 + 1e-4), thick)
