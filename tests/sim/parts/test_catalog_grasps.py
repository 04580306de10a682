"""The catalog parts' grasps synthesised from their meshes (sim.parts.catalog_grasps)."""

import numpy as np
import pytest

from sim.errors import SimInputError
from sim.parts import catalog_grasps
from sim.skills.grasps import load_grasps
from sim.world.config import WorldConfig
from sim.world.parts import cell_parts


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("PSORR_CACHE", str(tmp_path))
    return tmp_path


def test_the_cell_grasps_catalog_parts_by_synthesised_grasps_made_once(cache, monkeypatch):
    heard = []
    parts = cell_parts(WorldConfig(workpieces=("u_channel",)), heard.append)
    grasps = parts["u_channel"].grasps
    assert grasps and all(g.name.startswith("synth_") for g in grasps)
    assert all(np.allclose(g.approach, [0, 0, -1]) for g in grasps)  # from above the upright part
    assert len(heard) == 1 and "u_channel" in heard[0]

    monkeypatch.setattr(catalog_grasps, "_synthesised", lambda *a: pytest.fail("synthesised again"))
    again = cell_parts(WorldConfig(workpieces=("u_channel",)), heard.append)["u_channel"].grasps
    assert [g.as_record() for g in again] == [g.as_record() for g in grasps]


def test_the_best_synthesised_grasp_spans_the_channel_as_the_hand_written_one_does(cache):
    """The hand-written grasps are the reference: the channel is held across its walls, 50 mm apart."""
    best = cell_parts(WorldConfig(workpieces=("u_channel",)), None)["u_channel"].grasps[0]
    reference = load_grasps()["u_channel"][0]
    assert best.width == pytest.approx(reference.width, abs=0.002)
    assert abs(best.closing @ reference.closing) > 0.99


def test_the_hand_written_grasps_are_kept_as_a_reference(cache):
    parts = cell_parts(WorldConfig(workpieces=("u_channel",), catalog_grasps="hand-written"), None)
    assert parts["u_channel"].grasps == load_grasps()["u_channel"]
    assert not list(cache.iterdir())  # nothing synthesised


def test_an_unknown_grasp_source_is_refused_naming_the_choices():
    with pytest.raises(SimInputError, match="synthesised, hand-written"):
        WorldConfig(catalog_grasps="drawn")


def test_the_first_synthesis_is_told_on_stderr_leaving_stdout_to_results(cache, capsys):
    """psorr-sim's --json prints exactly one line on stdout: news of a slow first synthesis goes to stderr."""
    cell_parts(WorldConfig(workpieces=("u_channel",)))
    out, err = capsys.readouterr()
    assert out == "" and "synthesising the grasps of u_channel" in err
