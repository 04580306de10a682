"""What recognition derives from each model once, kept on disk (psorr.library.derived): read back equal to what
was derived, derived again when it cannot be read, and a folder that cannot be written only warned about."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
import trimesh

import psorr.acceptance.ambiguity as ambiguity
import psorr.library.derived as derived_module
import psorr.synthetic.resting as resting
from psorr.library.derived import derived


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("PSORR_CACHE", str(tmp_path))
    return tmp_path


def _counting(value):
    calls = []

    def derive():
        calls.append(1)
        return value
    return derive, calls


def _encode(value):
    return {"a": value[0], "b": np.float64(value[1])}


def _decode(arrays):
    return arrays["a"], float(arrays["b"])


def test_a_value_is_derived_once_and_read_back_equal(cache):
    value = (np.arange(12.0).reshape(3, 4) / 7, 0.1 + 0.2)
    derive, calls = _counting(value)
    inputs = (np.ones((5, 3)), 2.5)
    first = derived("thing", inputs, derive, _encode, _decode)
    again = derived("thing", inputs, derive, _encode, _decode)
    assert len(calls) == 1 and (cache / "derived").is_dir()
    assert np.array_equal(again[0], value[0]) and again[1] == value[1] and first is value
    derived("thing", (np.ones((5, 3)), 2.6), derive, _encode, _decode)  # other inputs: derived again
    assert len(calls) == 2


def test_an_entry_that_cannot_be_read_is_derived_again(cache):
    value = (np.zeros(3), 1.0)
    derive, calls = _counting(value)
    derived("thing", (np.ones(2),), derive, _encode, _decode)
    for entry in (cache / "derived").iterdir():
        entry.write_bytes(b"torn")
    assert derived("thing", (np.ones(2),), derive, _encode, _decode)[1] == 1.0
    assert len(calls) == 2


def test_a_folder_that_cannot_be_written_is_warned_about_once(tmp_path, monkeypatch):
    (tmp_path / "file").write_text("not a folder")
    monkeypatch.setenv("PSORR_CACHE", str(tmp_path / "file"))
    monkeypatch.setattr(derived_module, "_WARNED", set())
    derive, calls = _counting((np.zeros(3), 1.0))
    with pytest.warns(UserWarning, match="cannot write the derived-model cache.*PSORR_CACHE"):
        derived("thing", (np.ones(2),), derive, _encode, _decode)
    with warnings.catch_warnings(record=True) as heard:
        warnings.simplefilter("always")
        derived("thing", (np.ones(2),), derive, _encode, _decode)
    assert not heard and len(calls) == 2


def test_resting_poses_read_back_equal(cache, monkeypatch):
    mesh = trimesh.creation.box((0.06, 0.04, 0.02)).difference(trimesh.creation.cylinder(0.008, 0.05))
    found = resting.stable_rests(mesh)
    monkeypatch.setattr(resting, "_RESTS", {})
    monkeypatch.setattr(resting, "_found_rests", lambda _: pytest.fail("derived again"))
    read = resting.stable_rests(mesh)
    assert len(read) == len(found) > 1
    for a, b in zip(found, read):
        assert np.array_equal(a.T_table_model, b.T_table_model) and np.array_equal(a.footprint, b.footprint)
        assert (a.probability, a.height) == (b.probability, b.height)


def test_near_symmetries_read_back_equal(cache, library, monkeypatch):
    found = [ambiguity.NearSymmetryResolver(m) for m in library.models]
    # Other model objects, as a new process has: not in the in-process memo, so read from the disk or failed.
    monkeypatch.setattr(ambiguity.NearSymmetryResolver, "_find", lambda *_: pytest.fail("derived again"))
    read = [ambiguity.NearSymmetryResolver(dataclasses.replace(m)) for m in library.models]
    assert any(len(f.turns) for f in found) and any(f.slide is not None for f in found)
    assert any(f.axis is not None for f in found)
    for a, b in zip(found, read):
        assert np.array_equal(a.turns, b.turns) and np.array_equal(a._exact_but_features, b._exact_but_features)
        assert (a.slide is None) == (b.slide is None) and (a.slide is None or np.array_equal(a.slide, b.slide))
        assert (a.axis is None) == (b.axis is None)
        assert a.axis is None or all(np.array_equal(x, y) for x, y in zip(a.axis, b.axis))
        assert (a._area, a._axis_reach) == (b._area, b._axis_reach)
