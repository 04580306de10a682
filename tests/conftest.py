"""Fixtures shared by test modules."""

import os

import pytest

from psorr.library.models import ModelLibrary
from psorr.synthetic.catalog import DEFAULT_CATALOG


def pytest_collection_modifyitems(config, items):
    """Modules marked ``long`` first. make test hands whole modules to two workers in collection order; the
    longest, collected last (tests/test_grasp_success.py), left one worker running alone at the end."""
    items.sort(key=lambda item: item.get_closest_marker("long") is None)  # stable: modules stay whole


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    """All 8 catalog parts (6+ models, as in the issue), trained into a fresh cache. A module that needs
    other models defines its own ``library``, which takes precedence."""
    os.environ["PSORR_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    return ModelLibrary.from_meshes(sorted((DEFAULT_CATALOG.parent / "meshes").glob("*.stl")))
