"""The psorr command line, run as a user would (its refusals, which need no interpreter of their own, in this one)."""

import json
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from psorr.cli import main
from psorr.io.clouds import write_cloud
from psorr.synthetic import primitive_scenes as synthetic
from psorr.types import PointCloud


def _run(*args):
    return subprocess.run([sys.executable, "-m", "psorr.cli", *args], capture_output=True, text=True, timeout=120)


def _here(capsys, *args) -> SimpleNamespace:
    """``psorr`` run in this process, as :func:`_run` reports it: refusals need no interpreter of their own (an
    unexpected exception fails the test as a traceback would)."""
    try:
        status = main(list(args))
    except SystemExit as exc:
        status = exc.code
    out = capsys.readouterr()
    return SimpleNamespace(returncode=status, stdout=out.out, stderr=out.err)


def _labels_and_picture_written(folder, cloud, n_items: int) -> None:
    """labels.npy holds one int64 per point of ``cloud`` (-1 for NaN points) up to n_items - 1, and pic.png
    is a PNG."""
    labels = np.load(folder / "labels.npy")
    assert labels.dtype == np.int64 and labels.shape == (len(cloud),)
    assert (labels[~cloud.valid_mask] == -1).all()
    assert labels.max() == n_items - 1
    assert (folder / "pic.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_decompose_writes_labels_json_and_picture(tmp_path):
    scene = synthetic.box_on_table(np.random.default_rng(0))
    cloud_path = tmp_path / "scene.pcd"
    write_cloud(cloud_path, scene.cloud)
    out = _run("decompose", str(cloud_path), "--out", str(tmp_path / "labels.npy"), "--json",
               "--png", str(tmp_path / "pic.png"))
    assert out.returncode == 0, out.stderr
    record = json.loads(out.stdout)  # exactly one JSON line on stdout
    assert set(record) == {"primitives", "edges", "stats"}
    assert record["stats"]["total_ms"] > 0
    first = record["primitives"][0]
    assert set(first) >= {"id", "kind", "params", "n_points", "centroid"}
    _labels_and_picture_written(tmp_path, scene.cloud, len(record["primitives"]))


def test_bad_file_gives_one_line_error_not_a_traceback(tmp_path, capsys):
    bad = tmp_path / "broken.pcd"
    bad.write_text("this is not a PCD file\n")
    out = _run("decompose", str(bad))
    assert out.returncode == 2
    assert "broken.pcd" in out.stderr and "Traceback" not in out.stderr
    missing = _here(capsys, "decompose", str(tmp_path / "nowhere.ply"))
    assert missing.returncode == 2 and "nowhere.ply" in missing.stderr


def test_a_cloud_too_small_to_decompose_is_named_with_the_fix(tmp_path, capsys):
    few = tmp_path / "few.xyz"
    few.write_text("0 0 1\n0.01 0 1\n0 0.01 1\n")
    out = _here(capsys, "decompose", str(few))
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "few.xyz" in out.stderr and "3 finite points" in out.stderr
    rng = np.random.default_rng(0)  # many points in five clumps: five voxels
    path = tmp_path / "clumps.npy"
    np.save(path, np.repeat(rng.uniform(-0.1, 0.1, (5, 3)) + [0, 0, 1], 100, axis=0) + rng.normal(0, 1e-4, (500, 3)))
    coarse = _here(capsys, "decompose", str(path))
    assert coarse.returncode == 2 and "clumps.npy" in coarse.stderr and "smaller --voxel-size" in coarse.stderr


def test_voxel_size_zero_is_refused_not_taken_for_the_default(tmp_path, capsys):
    scene = synthetic.box_on_table(np.random.default_rng(0))
    path = tmp_path / "scene.npy"
    np.save(path, scene.cloud.points)
    for size in ("0", "-1", "nan", "inf", "5"):  # 5: millimetres, 1000x too big
        out = _here(capsys, "decompose", str(path), "--voxel-size", size)
        assert out.returncode == 2 and f"--voxel-size: expected a voxel size in metres from 0.001 to 0.1, got " \
            f"'{size}'" in out.stderr


def test_a_noise_scale_out_of_range_is_refused_and_one_in_range_reaches_the_recognizer(tmp_path, capsys,
                                                                                    monkeypatch):
    for scale in ("0", "-1", "nan", "20", "x"):
        out = _here(capsys, "recognize", str(tmp_path / "a.stl"), str(tmp_path / "b.npy"), "--noise-scale", scale)
        assert out.returncode == 2 and "--noise-scale: expected the sensor's noise as a multiple" in out.stderr
    import trimesh

    from psorr.recognize import Recognizer
    from psorr.sensing import KINECT_V1

    trimesh.creation.box(extents=(0.08, 0.05, 0.03)).export(tmp_path / "block.stl")
    scene = synthetic.box_on_table(np.random.default_rng(0))
    np.save(tmp_path / "scene.npy", scene.cloud.points)
    given = []

    def recorded(recognizer, *args, **kwargs):
        given.append(recognizer.params.sensor)
        raise _Stop

    monkeypatch.setattr(Recognizer, "recognize", recorded)
    with pytest.raises(_Stop):
        main(["recognize", str(tmp_path / "block.stl"), str(tmp_path / "scene.npy"), "--noise-scale", "2"])
    assert given[0].sigma_base == 2 * KINECT_V1.sigma_base and given[0].sigma_quad == 2 * KINECT_V1.sigma_quad
    assert given[0].disparity_step_px == KINECT_V1.disparity_step_px


class _Stop(Exception):
    """Raised in place of a recognition whose settings are all a test needs."""


def test_help_states_the_decomposition_default_voxel_size(capsys):
    from psorr.cli import DEFAULT_VOXEL_SIZE
    from psorr.decomposition import DecomposeParams

    assert DEFAULT_VOXEL_SIZE == DecomposeParams().voxel_size
    assert f"(default {DEFAULT_VOXEL_SIZE})" in _here(capsys, "decompose", "--help").stdout


def test_recognize_reads_the_scene_before_it_trains_models(tmp_path, capsys):
    # Training new meshes can take a while; a mistyped scene path should be reported at once.
    mesh = tmp_path / "not_a_mesh.stl"
    mesh.write_text("never read")
    out = _here(capsys, "recognize", str(mesh), str(tmp_path / "missing.pcd"), "--json")
    assert out.returncode == 2 and out.stdout == ""
    assert "missing.pcd" in out.stderr and "training" not in out.stderr and "not_a_mesh" not in out.stderr


def test_an_unwritable_cache_is_one_warning_line_and_recognition_runs(tmp_path):
    import os

    from psorr.synthetic.catalog import DEFAULT_CATALOG

    scene = synthetic.box_on_table(np.random.default_rng(0))
    write_cloud(tmp_path / "scene.pcd", scene.cloud)
    (tmp_path / "a_file").write_text("no folder can be made under a file")
    env = dict(os.environ, PSORR_CACHE=str(tmp_path / "a_file" / "cache"))
    out = subprocess.run([sys.executable, "-m", "psorr.cli", "recognize", str(DEFAULT_CATALOG.parent / "meshes" /
                          "bushing.stl"), str(tmp_path / "scene.pcd"), "--json"], capture_output=True, text=True,
                         timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    assert "Traceback" not in out.stderr and "library.py" not in out.stderr
    assert "psorr recognize: warning: cannot write the training cache" in out.stderr
    assert set(json.loads(out.stdout)) == {"detections", "stats"}


def test_a_cloud_in_millimetres_is_refused_with_the_fix(tmp_path, capsys):
    scene = synthetic.box_on_table(np.random.default_rng(0))
    path = tmp_path / "scene_mm.ply"
    write_cloud(path, PointCloud(scene.cloud.points * 1000.0))
    for args in (("decompose", str(path)), ("recognize", str(tmp_path / "no_meshes_needed.stl"), str(path))):
        out = _here(capsys, *args)
        assert out.returncode == 2 and "Traceback" not in out.stderr
        assert "scene_mm.ply" in out.stderr and "millimetres: scale it by 0.001" in out.stderr
        assert "training" not in out.stderr  # refused before any model is trained


def test_stacked_reports_a_block_flush_with_a_larger_one_that_the_default_takes_for_part_of_it(tmp_path):
    import trimesh

    from psorr.synthetic.workpiece_scenes import workpiece_scene

    def block(x, y, z):
        return trimesh.creation.box(extents=(x, y, z)).apply_translation((0, 0, z / 2))

    block(0.08, 0.06, 0.06).export(tmp_path / "small.stl")
    # Seed 1's layout: the small block's faces fit the large block's top and side (tests/test_continuation.py).
    scene = workpiece_scene(np.random.default_rng(1), {"large": block(0.24, 0.16, 0.06)}, ["large"])
    with pytest.warns(UserWarning, match="no image layout"):  # the CLI reads it unorganised: fine here
        write_cloud(tmp_path / "scene.ply", scene.cloud)  # float64: PCD's float32 moves this marginal find
    found = {}
    for flags in ((), ("--stacked",)):
        out = _run("recognize", str(tmp_path / "small.stl"), str(tmp_path / "scene.ply"), "--json", *flags)
        assert out.returncode == 0, out.stderr
        found[flags] = json.loads(out.stdout)["detections"]
    assert found[()] == [] and [d["model"] for d in found[("--stacked",)]] == ["small"]


def test_outputs_that_cannot_be_written_are_refused_before_any_work(tmp_path, capsys):
    scene = synthetic.box_on_table(np.random.default_rng(0))
    path = tmp_path / "scene.npy"
    np.save(path, scene.cloud.points)
    cases = [(("decompose", str(path), "--out", str(tmp_path / "labels.bin")), "must be a .npy file name"),
             (("decompose", str(path), "--png", str(tmp_path)), "must be a .png file name"),
             (("decompose", str(path), "--png", "/proc/no/x.png"), "cannot write there"),
             (("recognize", str(tmp_path / "never_read.stl"), str(path), "--png", "/proc/x.png"), "cannot write there")]
    for args, why in cases:
        out = _here(capsys, *args)
        assert out.returncode == 2 and why in out.stderr and "Traceback" not in out.stderr, out.stderr
        assert "read " not in out.stderr and "training" not in out.stderr  # refused before reading or training
    assert not (tmp_path / "labels.bin.npy").exists()


def test_recognize_refuses_a_cloud_no_sensor_at_the_origin_could_see(tmp_path, capsys):
    points = synthetic.box_on_table(np.random.default_rng(0)).cloud.points
    world = points - [0.0, 0.0, np.nanmedian(points[:, 2])]  # a table about z = 0, as in a world frame
    flipped = points * [1.0, -1.0, -1.0]  # z towards the sensor
    for name, cloud in (("world.npy", world), ("flipped.npy", flipped)):
        np.save(tmp_path / name, cloud)
        out = _here(capsys, "recognize", str(tmp_path / "never_read.stl"), str(tmp_path / name), "--json")
        assert out.returncode == 2 and out.stdout == "" and "Traceback" not in out.stderr
        assert name in out.stderr and "behind the sensor" in out.stderr and "sensor's frame" in out.stderr


def test_segment_writes_labels_json_and_picture(tmp_path):
    rng = np.random.default_rng(0)
    scene = synthetic.box_on_table(rng)
    colours = np.where(scene.cloud.labels[:, None] > 0, (0.8, 0.1, 0.1), (0.5, 0.5, 0.5))
    cloud_path = tmp_path / "scene.pcd"
    write_cloud(cloud_path, PointCloud(scene.cloud.points, colors=colours, width=scene.cloud.width,
                                       height=scene.cloud.height))
    out = _run("segment", str(cloud_path), "--out", str(tmp_path / "labels.npy"), "--json",
               "--png", str(tmp_path / "pic.png"))
    assert out.returncode == 0, out.stderr
    record = json.loads(out.stdout)  # exactly one JSON line on stdout
    assert set(record) == {"segments", "stats"} and record["stats"]["total_ms"] > 0
    assert set(record["segments"][0]) == {"id", "n_points", "centroid", "mean_rgb"}
    _labels_and_picture_written(tmp_path, scene.cloud, len(record["segments"]))


def test_segment_splits_stacked_boxes_at_their_crease_unless_told_not_to(tmp_path):
    from coloured_scenes import RED, stacked_boxes

    cloud, _ = stacked_boxes((RED, RED))
    write_cloud(tmp_path / "stacked.pcd", cloud)
    counts = []
    for extra in ([], ["--no-creases"]):
        out = _run("segment", str(tmp_path / "stacked.pcd"), "--json", *extra)
        assert out.returncode == 0, out.stderr
        counts.append(len([s for s in json.loads(out.stdout)["segments"] if s["n_points"] > 500]))
    assert counts == [2, 1]


def test_recognize_with_colour_reports_each_detection_s_colour(tmp_path):
    from coloured_scenes import BLUE, RED, two_boxes
    from part_meshes import box

    cloud, _ = two_boxes((RED, BLUE), gap=0.0)
    write_cloud(tmp_path / "scene.pcd", cloud)
    (tmp_path / "models").mkdir()
    box((0.10, 0.06, 0.05)).export(tmp_path / "models" / "box.stl")
    out = _run("recognize", str(tmp_path / "models"), str(tmp_path / "scene.pcd"), "--colour", "--json")
    assert out.returncode == 0, out.stderr
    detections = json.loads(out.stdout)["detections"]
    assert sorted(d["colour"] for d in detections) == ["blue", "red"]
    assert all(len(d["mean_rgb"]) == 3 for d in detections)


@pytest.mark.parametrize("method", ["psg", "auto"])
def test_recognize_with_method_psg_finds_a_single_chassis(tmp_path, method):
    from psorr.synthetic.catalog import load_catalog
    from psorr.synthetic.workpiece_scenes import workpiece_scene

    chassis = load_catalog()["chassis"]
    scene = workpiece_scene(np.random.default_rng(3), {"chassis": chassis.load_mesh()}, ["chassis"])
    write_cloud(tmp_path / "scene.pcd", scene.cloud)
    out = _run("recognize", str(chassis.mesh_path), str(tmp_path / "scene.pcd"), "--method", method, "--json")
    assert out.returncode == 0, out.stderr
    record = json.loads(out.stdout)
    assert [d["model"] for d in record["detections"]] == ["chassis"]
    found = np.array(record["detections"][0]["pose"])
    assert np.linalg.norm(found[:3, 3] - scene.instances[0].T_camera_model[:3, 3]) < 0.005
    assert record["stats"]["method"] == method and record["stats"]["qpbo_nodes"] > 0


def test_the_json_record_of_a_detection_holds_what_the_view_left_open():
    from psorr.cli import _left_open_record
    from psorr.types import Detection, Rival, UnfixedTurn

    turned = np.diag([-1.0, -1.0, 1.0, 1.0])
    detection = Detection("clip", np.eye(4), 0.8, alternatives=(turned,), rivals=(Rival("clip_8mm", np.eye(4), 0.7),))
    record = json.loads(json.dumps(_left_open_record(detection)))
    assert record["alternatives"] == [turned.tolist()]
    assert record["rivals"] == [{"model": "clip_8mm", "pose": np.eye(4).tolist(), "score": 0.7}]
    assert _left_open_record(Detection("clip", np.eye(4), 0.8)) == {}
    pulley = Detection("pulley", np.eye(4), 0.8, unfixed_turn=UnfixedTurn([0.0, 0.0, 0.01], [0.0, 0.0, 1.0]))
    assert json.loads(json.dumps(_left_open_record(pulley))) == {
        "unfixed_turn": {"point": [0.0, 0.0, 0.01], "direction": [0.0, 0.0, 1.0]}}


def test_train_saves_a_library_that_recognize_takes(tmp_path, capsys):
    import trimesh

    from psorr.synthetic.workpiece_scenes import workpiece_scene

    parts = {"block": trimesh.creation.box(extents=(60.0, 40.0, 30.0)),
             "rod": trimesh.creation.cylinder(radius=12.0, height=70.0, sections=64)}
    for name, mesh in parts.items():
        mesh.export(tmp_path / f"{name}.stl")  # millimetres, as CAD exports are
    out = _here(capsys, "train", str(tmp_path), "--units", "mm", "--out", str(tmp_path / "lib.npz"), "--json")
    assert out.returncode == 0, out.stderr
    record = json.loads(out.stdout)
    assert [m["model"] for m in record["models"]] == ["block", "rod"]
    assert record["models"][0]["diameter_m"] == pytest.approx(np.linalg.norm([0.06, 0.04, 0.03]), rel=0.02)  # samples
    assert record["models"][0]["planes"] >= 3 and record["models"][1]["cylinders"] >= 1
    block = parts["block"].copy().apply_scale(0.001)
    scene = workpiece_scene(np.random.default_rng(0), {"block": block.apply_translation((0, 0, 0.015))}, ["block"])
    write_cloud(tmp_path / "scene.pcd", scene.cloud)
    found = _here(capsys, "recognize", str(tmp_path / "lib.npz"), str(tmp_path / "scene.pcd"), "--json")
    assert found.returncode == 0, found.stderr
    assert [d["model"] for d in json.loads(found.stdout)["detections"]] == ["block"]


def test_train_refuses_a_saved_library_and_an_output_that_is_no_library(tmp_path, capsys):
    out = _here(capsys, "train", str(tmp_path / "lib.npz"), "--out", str(tmp_path / "again.npz"))
    assert out.returncode != 0 and "is a saved library: psorr train takes meshes" in out.stderr
    out = _here(capsys, "train", str(tmp_path), "--out", str(tmp_path / "lib.stl"))
    assert out.returncode != 0 and "must be a .npz file name" in out.stderr
