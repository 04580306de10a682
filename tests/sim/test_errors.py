"""The sim's exception hierarchy (sim/errors.py): one root under psorr's, and bad input still psorr's
InvalidInputError, so callers' handlers keep working."""

import importlib
import inspect
import pkgutil

import numpy as np
import pytest

import sim
from psorr.errors import CloudFileError, InvalidInputError, PsorrError
from sim.errors import SimError, SimInputError, TaskFileError
from sim.world import WorldConfig, build_world, load_task


def _sim_modules():
    for info in pkgutil.walk_packages(sim.__path__, "sim."):
        yield importlib.import_module(info.name)


def test_every_error_the_sim_defines_derives_from_its_root():
    defined = {cls for module in _sim_modules() for _, cls in inspect.getmembers(module, inspect.isclass)
               if issubclass(cls, BaseException) and cls.__module__.startswith("sim.")}
    assert len(defined) >= 9
    assert all(issubclass(cls, SimError) for cls in defined), sorted(c.__name__ for c in defined)
    assert issubclass(SimError, PsorrError)


def test_bad_input_is_still_psorrs_invalid_input_and_a_value_error():
    assert issubclass(SimInputError, InvalidInputError) and issubclass(SimInputError, ValueError)
    assert issubclass(TaskFileError, CloudFileError)
    with pytest.raises(SimInputError, match=r"\[0.6, 1.0\]"):
        WorldConfig(camera_height=1.5)
    with pytest.raises(InvalidInputError, match="choose from"):
        build_world(WorldConfig(workpieces=("gear",)), np.random.default_rng(0))


def test_a_bad_task_file_is_a_sim_error_naming_the_file(tmp_path):
    task = tmp_path / "task.yaml"
    task.write_text("workpieces: [gear]\n")
    with pytest.raises(TaskFileError, match=r"task\.yaml: line 1: unknown workpiece 'gear' \(name catalog") as info:
        load_task(task)
    assert isinstance(info.value, SimError) and info.value.path == str(task)
