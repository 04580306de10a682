"""The sim's modes (sim/modes.py): enums that plain strings still select, refused naming the choices."""

import os

import pytest

from psorr.errors import InvalidInputError
from sim.cli import build_parser
from sim.devices.render_backend import HeadlessBackend, ensure_headless_gl
from sim.modes import PoseSource, choices, parse_mode


def test_a_mode_is_its_string_and_strings_still_select_it():
    assert PoseSource.ORACLE == "oracle" and f"{PoseSource.RECOGNIZED}" == "recognized"
    assert parse_mode(PoseSource, "oracle", "poses") is PoseSource.ORACLE
    assert parse_mode(PoseSource, PoseSource.RECOGNIZED, "poses") is PoseSource.RECOGNIZED
    with pytest.raises(InvalidInputError, match=r"poses must be one of \['recognized', 'oracle'\], got 'guess'"):
        parse_mode(PoseSource, "guess", "poses")


def test_the_command_line_takes_its_choices_from_the_enum():
    parser = build_parser()
    assert parser.parse_args(["run", "task.yaml"]).poses == PoseSource.RECOGNIZED
    for source in PoseSource:
        assert parser.parse_args(["run", "task.yaml", "--poses", source.value]).poses == source
    with pytest.raises(SystemExit):
        parser.parse_args(["run", "task.yaml", "--poses", "guess"])


def test_the_headless_backend_in_use_is_one_of_the_enum_or_the_users_own():
    backend = ensure_headless_gl()
    assert backend == os.environ["MUJOCO_GL"]
    if backend in choices(HeadlessBackend):
        assert isinstance(backend, HeadlessBackend)
