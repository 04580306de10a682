"""Training from CAD: point-pair features, the library file and its cache, units."""

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from psorr.errors import CloudFileError, InvalidInputError
from psorr.library import models as library_module
from psorr.library.models import ModelLibrary, load_mesh_in_metres
from psorr.library.ppf import HashParams, PairTable, invert_rigid, pair_frames
from psorr.synthetic.catalog import DEFAULT_CATALOG

MESHES = DEFAULT_CATALOG.parent / "meshes"


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("PSORR_CACHE", str(tmp_path / "cache"))


def test_a_matched_pair_gives_the_exact_rigid_motion():
    rng = np.random.default_rng(0)
    p1, p2 = rng.normal(size=(20, 3)), rng.normal(size=(20, 3))
    n1 = rng.normal(size=(20, 3))
    n1 /= np.linalg.norm(n1, axis=1, keepdims=True)
    n2 = rng.normal(size=(20, 3))
    n2 /= np.linalg.norm(n2, axis=1, keepdims=True)
    points, normals = np.vstack([p1, p2]), np.vstack([n1, n2])
    table = PairTable.build(HashParams(), points, normals, np.zeros(40), np.arange(40), np.arange(20),
                            np.arange(20, 40))
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = Rotation.random(random_state=1).as_matrix(), (0.3, -0.2, 1.0)
    moved = lambda x: x @ T[:3, :3].T  # noqa: E731
    s, rows = table.lookup(moved(p1) + T[:3, 3], moved(n1), moved(p2) + T[:3, 3], moved(n2))
    own = s == table.first[rows]  # each scene pair against its own model pair
    assert own.sum() == 20
    poses, _ = table.poses(s[own], rows[own], moved(p1) + T[:3, 3], moved(n1), moved(p2) + T[:3, 3])
    assert np.allclose(poses, T, atol=1e-9)
    frames = pair_frames(p1, n1, p2)
    assert np.allclose(frames @ invert_rigid(frames), np.eye(4), atol=1e-12)


def test_library_saves_loads_and_caches(tmp_path, monkeypatch):
    paths = [MESHES / "flanged_hub.stl", MESHES / "u_channel.stl"]
    lib = ModelLibrary.from_meshes(paths)
    assert lib.names == ["flanged_hub", "u_channel"] and len(lib.table) > 1000
    assert [p.kind.value for p in lib.model("flanged_hub").graph.primitives].count("cylinder") >= 3
    saved = lib.save(tmp_path / "lib.npz")
    again = ModelLibrary.load(saved)
    assert again.names == lib.names and len(again.table) == len(lib.table)
    assert np.array_equal(again.model("u_channel").points, lib.model("u_channel").points)

    def no_training(*args, **kwargs):
        raise AssertionError("a cached model was trained again")

    monkeypatch.setattr(library_module, "train_model", no_training)
    cached = ModelLibrary.from_meshes(paths)
    assert np.array_equal(cached.table.keys, lib.table.keys)


def test_a_model_cached_by_other_training_code_is_trained_again(monkeypatch):
    # An upgrade that changes training (the decomposition, say) must not reuse the models the old code made.
    from psorr.library import cache as training_cache

    paths = [MESHES / "u_channel.stl"]
    ModelLibrary.from_meshes(paths)
    trained = []
    real_train = library_module.train_model
    monkeypatch.setattr(library_module, "train_model", lambda *a, **k: trained.append(a[0]) or real_train(*a, **k))
    ModelLibrary.from_meshes(paths)
    assert trained == []  # same code: from the cache
    monkeypatch.setattr(training_cache, "code_fingerprint", lambda: "other code")
    ModelLibrary.from_meshes(paths)
    assert trained == ["u_channel"]


def test_two_writers_of_one_cache_file_both_succeed(tmp_path, monkeypatch):
    # Two processes training one mesh into one cache: the second finishes while the first is between
    # writing its file and moving it into place. With one shared temporary name, the second moved the
    # first's file away and the first failed with FileNotFoundError.
    from psorr.library import file_format as library_file

    lib = ModelLibrary.from_meshes([MESHES / "u_channel.stl"])
    target = tmp_path / "written" / "u_channel.npz"
    real_savez, nested = np.savez_compressed, []

    def savez_then_other_writer(file, **arrays):
        real_savez(file, **arrays)
        if not nested:
            nested.append(True)
            library_file.save_models(target, lib.models)

    monkeypatch.setattr(library_file.np, "savez_compressed", savez_then_other_writer)
    library_file.save_models(target, lib.models)
    monkeypatch.undo()
    assert nested and ModelLibrary.load(target).names == ["u_channel"]
    assert [p.name for p in target.parent.iterdir()] == ["u_channel.npz"]  # no temporary left behind


def test_an_unwritable_cache_warns_and_training_still_succeeds(tmp_path, monkeypatch):
    blocker = tmp_path / "a_file"
    blocker.write_text("the cache folder cannot be made under a file")
    monkeypatch.setenv("PSORR_CACHE", str(blocker / "cache"))
    with pytest.warns(UserWarning, match=r"cannot write the training cache .*a_file.*set PSORR_CACHE"):
        lib = ModelLibrary.from_meshes([MESHES / "u_channel.stl", MESHES / "bushing.stl"])
    assert lib.names == ["u_channel", "bushing"] and len(lib.table) > 1000


def test_implausible_size_needs_units(tmp_path):
    mesh = trimesh.creation.box(extents=(100.0, 60.0, 40.0))  # millimetres
    path = tmp_path / "block.stl"
    mesh.export(path)
    with pytest.raises(CloudFileError, match="block.stl.*--units mm"):
        load_mesh_in_metres(path)
    assert np.allclose(load_mesh_in_metres(path, "mm").extents, (0.1, 0.06, 0.04))


def test_a_mesh_in_inches_or_centimetres_is_scaled_to_metres(tmp_path):
    trimesh.creation.box(extents=(4.0, 2.5, 1.0)).export(tmp_path / "bracket.stl")
    assert np.allclose(load_mesh_in_metres(tmp_path / "bracket.stl", "in").extents, (0.1016, 0.0635, 0.0254))
    assert np.allclose(load_mesh_in_metres(tmp_path / "bracket.stl", "cm").extents, (0.04, 0.025, 0.01))


def test_a_tiny_mesh_is_not_told_to_shrink_further(tmp_path):
    path = tmp_path / "speck.stl"
    trimesh.creation.box(extents=(0.0007, 0.0005, 0.0004)).export(path)
    with pytest.raises(CloudFileError, match="speck.stl.*under 5 mm") as refused:
        load_mesh_in_metres(path)
    assert "--units mm" not in str(refused.value)


def test_given_units_that_make_a_part_implausible_are_taken_and_said(tmp_path):
    path = tmp_path / "block.stl"
    trimesh.creation.box(extents=(0.1, 0.06, 0.04)).export(path)  # metres, read as millimetres
    with pytest.warns(UserWarning, match=r"block.stl: in mm the mesh is 0.1 mm across.*check --units"):
        mesh = load_mesh_in_metres(path, "mm")
    assert np.allclose(mesh.extents, (1e-4, 6e-5, 4e-5))


def test_not_a_library_is_a_clear_error(tmp_path):
    bad = tmp_path / "models.npz"
    bad.write_bytes(b"nonsense")
    with pytest.raises(CloudFileError, match="models.npz"):
        ModelLibrary.load(bad)


def test_a_folder_without_meshes_names_the_subfolder_that_has_them(tmp_path):
    from psorr.library.sources import library_from_arguments
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box(extents=(0.1, 0.06, 0.04)).export(tmp_path / "meshes" / "block.stl")
    (tmp_path / "empty").mkdir()
    with pytest.raises(CloudFileError, match="no .* meshes .*one level down: pass .*meshes"):
        library_from_arguments([tmp_path])
    with pytest.raises(CloudFileError, match="empty: .*pass a folder of meshes"):
        library_from_arguments([tmp_path / "empty"])


def test_a_flat_mesh_trains(tmp_path, monkeypatch):
    # Its convex hull has no volume: trimesh's hull then wanted networkx, which we do not install.
    monkeypatch.setenv("PSORR_CACHE", str(tmp_path / "cache"))
    sheet = trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], [[0, 1, 2]])
    sheet.export(tmp_path / "sheet.stl")
    with pytest.warns(UserWarning, match="sheet.stl: the mesh is not closed"):
        model = ModelLibrary.from_meshes([tmp_path / "sheet.stl"]).models[0]
    assert 0.12 < model.diameter <= np.sqrt(2) * 0.1 + 1e-9


def test_two_meshes_with_one_name_are_refused_before_training(tmp_path, monkeypatch):
    trained = []
    monkeypatch.setattr(library_module, "train_model", lambda *a, **k: trained.append(a))
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for folder in ("a", "b"):
        trimesh.creation.box(extents=(0.1, 0.06, 0.04)).export(tmp_path / folder / "block.stl")
    with pytest.raises(InvalidInputError, match=r"a/block.stl and .*b/block.stl would both be the model 'block'"):
        ModelLibrary.from_meshes([tmp_path / "a" / "block.stl", tmp_path / "b" / "block.stl"], use_cache=False)
    assert trained == []


def test_bad_settings_name_the_field():
    from psorr.acceptance.continuation import ContinuationParams
    from psorr.acceptance.params import AcceptParams
    from psorr.hypotheses.pairs import PairParams
    from psorr.library.models import TrainParams

    with pytest.raises(Exception, match="refine_top"):
        PairParams(refine_top=0)
    with pytest.raises(Exception, match="min_visible_fraction"):
        AcceptParams(min_visible_fraction=1.5)
    with pytest.raises(Exception, match="max_continued must lie in"):
        AcceptParams(max_continued=2.0)
    assert AcceptParams(max_continued=None).max_continued is None  # the check can be turned off
    with pytest.raises(InvalidInputError, match="min_support_above_table must be >= 0"):
        AcceptParams(min_support_above_table=-1)
    assert AcceptParams(min_support_above_table=0).min_support_above_table == 0  # and this one
    with pytest.raises(InvalidInputError, match="ContinuationParams.neighbours"):
        ContinuationParams(neighbours=0)
    with pytest.raises(InvalidInputError, match="ContinuationParams.ring"):
        ContinuationParams(ring=0.0)
    with pytest.raises(Exception, match="TrainParams"):
        TrainParams(sample_spacing=0)


def test_an_inside_out_mesh_is_turned_right_side_out_and_said(tmp_path):
    # Its normals all pointed into the part, and the transformer was then found nowhere, without a word.
    mesh = trimesh.load(MESHES / "u_channel.stl")
    mesh.invert()
    mesh.export(tmp_path / "inside_out.stl")
    with pytest.warns(UserWarning, match="inside_out.stl: the mesh is inside out"):
        turned = load_mesh_in_metres(tmp_path / "inside_out.stl")
    assert turned.volume > 0
    np.testing.assert_allclose(turned.volume, trimesh.load(MESHES / "u_channel.stl").volume)


def test_a_mesh_whose_faces_disagree_on_outward_is_refused_with_the_fix(tmp_path):
    mesh = trimesh.load(MESHES / "u_channel.stl")
    faces = mesh.faces.copy()
    faces[::3] = faces[::3, ::-1]
    trimesh.Trimesh(mesh.vertices, faces, process=False).export(tmp_path / "mixed.stl")
    with pytest.raises(CloudFileError, match="mixed.stl: its faces disagree on which way is out.*re-orient"):
        load_mesh_in_metres(tmp_path / "mixed.stl")


def test_an_obj_of_several_objects_is_trained_as_one_model_and_said(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.load(MESHES / "bushing.stl"), "bushing")
    scene.add_geometry(trimesh.load(MESHES / "u_channel.stl").apply_translation([0.3, 0, 0]), "u_channel")
    scene.export(tmp_path / "two.obj")
    with pytest.warns(UserWarning, match=r"two.obj: holds 2 meshes \(bushing.*, u_channel.*\), trained as one"):
        load_mesh_in_metres(tmp_path / "two.obj")


def test_a_mesh_file_of_another_format_says_so(tmp_path):
    (tmp_path / "part.obj").write_bytes((MESHES / "bushing.stl").read_bytes())  # binary STL named .obj
    with pytest.raises(CloudFileError, match=r"part.obj: holds no faces: .*not a .obj file"):
        load_mesh_in_metres(tmp_path / "part.obj")


def test_an_empty_or_mixed_in_saved_library_is_named(tmp_path):
    from psorr.library.sources import library_from_arguments

    (tmp_path / "empty.npz").write_bytes(b"")
    with pytest.raises(CloudFileError, match="empty.npz: the file is empty"):
        ModelLibrary.load(tmp_path / "empty.npz")
    saved = ModelLibrary.from_meshes([MESHES / "bushing.stl"]).save(tmp_path / "lib.npz")
    with pytest.raises(CloudFileError, match="lib.npz: is a saved library, given with other MODELS"):
        library_from_arguments([saved, MESHES / "u_channel.stl"])


def test_saving_where_it_cannot_be_written_and_passing_a_mesh_object_are_named(tmp_path):
    lib = ModelLibrary.from_meshes([MESHES / "bushing.stl"])
    (tmp_path / "a_file").write_text("not a folder")
    with pytest.raises(CloudFileError, match="lib.npz: cannot be written"):
        lib.save(tmp_path / "a_file" / "lib.npz")
    with pytest.raises(InvalidInputError, match="takes paths of mesh files, got a Trimesh: export it"):
        ModelLibrary.from_meshes([trimesh.load(MESHES / "bushing.stl")])


def test_a_file_that_cannot_be_created_is_reported_as_such(tmp_path, monkeypatch):
    # The clean-up of the temporary file raised FileNotFoundError over the real error when the temporary
    # itself could not be created, and the warning then named the wrong reason.
    from psorr.library import file_format as library_file

    def no_permission(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    lib = ModelLibrary.from_meshes([MESHES / "bushing.stl"])
    monkeypatch.setattr(library_file, "open", no_permission, raising=False)
    with pytest.raises(CloudFileError, match="lib.npz: cannot be written \\(Permission denied\\)"):
        lib.save(tmp_path / "lib.npz")
    assert not any(p.name.startswith("lib.npz") for p in tmp_path.iterdir())  # nothing half-written left


def test_a_cache_that_cannot_be_written_still_serves_what_it_holds(monkeypatch):
    from psorr.library import cache as training_cache

    ModelLibrary.from_meshes([MESHES / "bushing.stl"])  # cached
    trained = []
    real_train = library_module.train_model
    monkeypatch.setattr(library_module, "train_model", lambda *a, **k: trained.append(a[0]) or real_train(*a, **k))

    def read_only(path, models):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(training_cache, "save_models", read_only)
    with pytest.warns(UserWarning, match="Permission denied") as caught:
        ModelLibrary.from_meshes([MESHES / "u_channel.stl", MESHES / "flanged_hub.stl", MESHES / "bushing.stl"])
    assert trained == ["u_channel", "flanged_hub"] and len(caught) == 1
