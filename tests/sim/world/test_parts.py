"""Which heights the cell expects its parts to stand to (sim.world.parts)."""

import numpy as np
import trimesh

from psorr.synthetic.catalog import WorkpieceInfo
from sim.world.config import WorldConfig
from sim.world.parts import standing_height


def _plate(tmp_path):
    path = tmp_path / "plate.stl"
    plate = trimesh.creation.box((0.08, 0.05, 0.006))
    plate.apply_translation([0, 0, 0.003])
    plate.export(path)
    return WorkpieceInfo("plate", path, 0.03, (0.5, 0.5, 0.5), [np.eye(4)], None)


def test_a_plate_upright_stands_as_thick_as_it_is(tmp_path):
    assert np.isclose(standing_height(WorldConfig(workpieces=("chassis",)), _plate(tmp_path)), 0.006)


def test_a_plate_lying_any_way_may_stand_on_its_end(tmp_path):
    """A drawn rest may stand the plate on its short edge, as tall as it is long: the perception ceiling must
    not crop it as an intrusion."""
    cfg = WorldConfig(workpieces=("chassis",), resting="any")
    assert np.isclose(standing_height(cfg, _plate(tmp_path)), 0.08, atol=1e-6)
