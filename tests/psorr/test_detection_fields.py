"""What a detection carries beside its pose refuses bad values with an error naming the field and the fix."""

import numpy as np
import pytest

from psorr.errors import InvalidInputError
from psorr.types import Rival, UnfixedTurn


def test_an_unfixed_turn_holds_a_point_and_a_unit_direction():
    turn = UnfixedTurn([0.0, 0.0, 0.01], (0.0, 0.0, 1.0))
    assert turn.point.shape == (3,) and turn.direction.shape == (3,) and not turn.direction.flags.writeable
    with pytest.raises(InvalidInputError, match=r"UnfixedTurn.direction must be a unit vector"):
        UnfixedTurn(np.zeros(3), [0.0, 0.0, 2.0])
    with pytest.raises(InvalidInputError, match=r"UnfixedTurn.point must have shape"):
        UnfixedTurn([0.0, 0.0], [0.0, 0.0, 1.0])


def test_a_rival_needs_a_rigid_pose():
    with pytest.raises(InvalidInputError, match=r"Rival.T_cloud_model"):
        Rival("clip", np.ones((4, 4)), 0.5)
