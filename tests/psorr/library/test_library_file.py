"""The library file: what it keeps (models and their training settings), and what it refuses."""

import json
import zipfile

import numpy as np
import pytest
import trimesh

from psorr.errors import CloudFileError
from psorr.library.models import ModelLibrary, TrainParams
from psorr.library.sources import library_from_arguments


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("PSORR_CACHE", str(tmp_path / "cache"))


@pytest.fixture
def block(tmp_path):
    path = tmp_path / "block.stl"
    trimesh.creation.box(extents=(0.1, 0.06, 0.04)).export(path)
    return path


def test_the_training_settings_come_back_with_the_models(tmp_path, block):
    lib = ModelLibrary.from_meshes([block], params=TrainParams(pair_points=4))
    again = ModelLibrary.load(lib.save(tmp_path / "lib.npz"))
    assert again.params == lib.params and again.params.pair_points == 4
    assert np.array_equal(again.table.keys, lib.table.keys)  # the pair table rebuilt as trained, not at 16


def _rewritten(source, target, change):
    """``source``'s archive written to ``target`` with ``change(name, bytes) -> bytes`` applied to each member."""
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            zout.writestr(item.filename, change(item.filename, zin.read(item.filename)))
    return target


def _meta(edit):
    def change(name, data):
        if name != "meta.npy":
            return data
        array = np.load(__import__("io").BytesIO(data))
        meta = json.loads(bytes(array).decode())
        edit(meta)
        out = __import__("io").BytesIO()
        np.save(out, np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8))
        return out.getvalue()
    return change


def test_damaged_or_foreign_files_are_refused_naming_the_file(tmp_path, block):
    good = ModelLibrary.from_meshes([block]).save(tmp_path / "good.npz")
    data = good.read_bytes()
    (tmp_path / "torn.npz").write_bytes(data[: len(data) // 2])
    np.save(tmp_path / "array.npy", np.zeros(3))
    (tmp_path / "array.npy").rename(tmp_path / "array.npz")
    _rewritten(good, tmp_path / "empty.npz", _meta(lambda m: m.update(models=[])))
    _rewritten(good, tmp_path / "twins.npz", _meta(lambda m: m.update(models=m["models"] * 2)))
    _rewritten(good, tmp_path / "typed.npz", _meta(lambda m: m.update(models=3)))

    def flat(name, data):
        if name != "m0_points.npy":
            return data
        out = __import__("io").BytesIO()
        np.save(out, np.zeros((10, 2)))
        return out.getvalue()

    _rewritten(good, tmp_path / "flat.npz", flat)
    for name in ("torn", "array", "empty", "twins", "typed", "flat", "absent"):
        with pytest.raises(CloudFileError, match=f"{name}.npz"):
            ModelLibrary.load(tmp_path / f"{name}.npz")


def test_units_with_a_saved_library_are_refused(tmp_path, block):
    saved = ModelLibrary.from_meshes([block]).save(tmp_path / "lib.npz")
    with pytest.raises(CloudFileError, match="leave out --units"):
        library_from_arguments([saved], units="mm")


def test_files_in_a_model_folder_that_are_not_meshes_are_named(tmp_path, block, capsys):
    (tmp_path / "part.IGES").write_text("ISO-10303-21;")
    (tmp_path / "README.md").write_text("notes")
    lib = library_from_arguments([tmp_path])
    assert lib.names == ["block"]
    assert "skipping 2 file(s)" in capsys.readouterr().err


def test_a_single_path_or_a_folder_is_not_a_list_of_meshes(tmp_path, block):
    with pytest.raises(Exception, match=r"pass \[path\]"):
        ModelLibrary.from_meshes(str(block))
    with pytest.raises(CloudFileError, match="is a folder"):
        ModelLibrary.from_meshes([tmp_path])
    with pytest.raises(Exception, match=r"glob\('\*.stl'\).*library_from_arguments"):
        ModelLibrary.from_meshes(tmp_path)


def test_a_generator_of_mesh_paths_trains_like_a_list(block):
    # The checks before training once spent the generator: "no mesh files given".
    assert ModelLibrary.from_meshes(p for p in [block]).names == ["block"]


def test_a_library_is_saved_as_npz_and_a_mesh_or_text_is_not_loaded_as_one(tmp_path, block):
    lib = ModelLibrary.from_meshes([block])
    with pytest.raises(CloudFileError, match=r"lib.txt: .*must end in .npz.*save to lib.npz"):
        lib.save(tmp_path / "lib.txt")
    assert not (tmp_path / "lib.txt").exists()
    with pytest.raises(CloudFileError, match=r"block.stl: is a mesh.*from_meshes"):
        ModelLibrary.load(block)
    (tmp_path / "notes.npz").write_text("not numpy at all")
    with pytest.raises(CloudFileError, match=r"notes.npz: not a psorr model library \(not an .npz archive\)") as caught:
        ModelLibrary.load(tmp_path / "notes.npz")
    assert "pickle" not in str(caught.value)  # numpy's message invites unpickling an untrusted file
