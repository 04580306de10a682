"""psorr.assets.asset_path: the package data's files by name, and a missing one named with its fix."""

import zipfile
from importlib.resources import files

import pytest

from psorr.assets import asset_path
from psorr.errors import AssetError, CloudFileError
from psorr.synthetic.catalog import DEFAULT_CATALOG


def test_asset_path_finds_the_package_data_through_importlib_resources():
    arm = asset_path("robot", "arm.xml")
    assert arm.is_file() and arm == files("psorr.assets") / "robot" / "arm.xml"
    assert asset_path("workpieces", "collision").is_dir()
    assert DEFAULT_CATALOG == asset_path("workpieces", "catalog.json")


def test_a_missing_asset_in_a_checkout_names_the_file_and_the_build_scripts():
    with pytest.raises(AssetError, match=r"no_such_part\.stl: no such psorr asset .*build_workpieces\.py") as info:
        asset_path("workpieces", "meshes", "no_such_part.stl")
    assert isinstance(info.value, CloudFileError) and info.value.path.endswith("no_such_part.stl")


def test_a_missing_asset_in_an_install_says_to_reinstall(tmp_path, monkeypatch):
    monkeypatch.setattr("psorr.assets.files", lambda package: tmp_path)  # package data without the build scripts
    with pytest.raises(AssetError, match=r"arm\.xml: no such psorr asset .*reinstall"):
        asset_path("robot", "arm.xml")


def test_assets_inside_a_zip_are_refused_since_mujoco_and_trimesh_open_files_by_name(tmp_path, monkeypatch):
    with zipfile.ZipFile(tmp_path / "psorr.zip", "w") as archive:
        archive.writestr("psorr/assets/robot/arm.xml", "<mujoco/>")
    monkeypatch.setattr("psorr.assets.files", lambda package: zipfile.Path(tmp_path / "psorr.zip", "psorr/assets/"))
    with pytest.raises(AssetError, match="not files on disk"):
        asset_path("robot", "arm.xml")
