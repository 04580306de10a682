"""Recording episodes (sim/recording/): the MP4, the contact sheet, the overlays and a bad --record DIR. Headless."""

from types import MappingProxyType, SimpleNamespace

import imageio
import imageio.v3 as iio
import numpy as np
import pytest
import trimesh

from psorr.errors import PsorrError
from psorr.types import Detection
from sim.devices.sensor import DepthCamera
from sim.episode import run_episode
from sim.errors import RecordingError
from sim.recording.recorder import EpisodeRecorder
from sim.skills.perception import Estimate, Look
from sim.world import WorldConfig, build_world

SEED = 8  # with u_channel alone the person is in view at the first looks, then the pick goes ahead
FPS = 10.0


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("record")
    world = build_world(WorldConfig(workpieces=("u_channel",)), np.random.default_rng(SEED))
    recorder = EpisodeRecorder(out / "new" / "dir", "ep", fps=FPS)
    result = run_episode(world, np.random.default_rng(SEED), poses="oracle", occluder=True, recorder=recorder)
    return out / "new" / "dir", recorder, result, recorder.close()


def test_close_returns_the_video_and_the_sheet(recorded):
    out, recorder, _, paths = recorded
    assert paths == [out / "ep.mp4", out / "ep_sheet.png"]
    assert all(p.is_file() and p.stat().st_size > 0 for p in paths)
    assert recorder.close() == paths  # closing again writes nothing new


def test_the_video_has_a_frame_per_tenth_of_a_sim_second_and_shows_something(recorded):
    out, _, result, _ = recorded
    reader = imageio.get_reader(out / "ep.mp4")
    try:
        frames = reader.count_frames()
        first, last = reader.get_data(0), reader.get_data(frames - 1)
        assert reader.get_meta_data()["fps"] == pytest.approx(FPS)
    finally:
        reader.close()
    assert abs(frames - result.sim_s * FPS) <= 2, (frames, result.sim_s)
    assert first.shape == (384, 960, 3)  # two 480x360 panels over a 24 px caption
    for frame in (first, last):
        assert frame.reshape(-1, 3).std(axis=0).max() > 10  # not one colour
    assert np.abs(first.astype(int) - last.astype(int)).mean() > 1  # the cell moved


def test_the_sheet_has_a_row_for_the_look_that_led_to_the_grasp(recorded):
    out, recorder, result, _ = recorded
    assert result.occupied_looks >= 1, "choose a SEED where the person is in view at a look"
    (row,) = recorder.rows  # looks that found the person are counted in the title, not drawn
    assert row.look == result.looks == result.occupied_looks + 1
    assert result.picks[0].grasp_name, "choose a SEED where the pick gets to close the gripper"
    assert row.grasp_part == "u_channel" and row.grasp.shape == (360, 480, 3)
    assert [o.name for o in row.overlays] == ["u_channel"] and row.overlays[0].score == 1.0
    sheet = iio.imread(out / "ep_sheet.png")
    assert sheet.shape[1] > sheet.shape[0] > 200  # one row of three panels: wider than tall


def test_overlays_land_on_the_part_in_the_image(tmp_path):
    """A detection at the true pose (recognised look, 640x480) and the oracle's truth (480x360 render)
    draw model points inside the part's silhouette."""
    world = build_world(WorldConfig(workpieces=("u_channel",)), np.random.default_rng(0))
    with DepthCamera(world.model, world.camera_name) as camera:
        frame = camera.render(world.data)
    T_world_part = world.body_pose("u_channel")
    T_camera_part = np.linalg.inv(frame.T_world_camera) @ T_world_part
    points = trimesh.sample.sample_surface(world.catalog["u_channel"].load_mesh(), 2000, seed=1)[0]
    library = SimpleNamespace(model=lambda name: SimpleNamespace(points=points))
    recognised = Look(frame, (Detection("u_channel", T_camera_part, 0.9),), MappingProxyType({}), 0, False)
    oracle = Look(None, (), MappingProxyType({"u_channel": (Estimate(T_world_part, 1.0),)}), 0, False)
    recorder = EpisodeRecorder(tmp_path, "looks")
    recorder.looked(world, world.data, recognised, library)
    recorder.looked(world, world.data, oracle, None)
    paths = recorder.close()

    silhouette = frame.segmentation == world.model.body("u_channel").id
    grown = silhouette.copy()  # 2 px of slack for rounding and the sampled mesh's edges
    for axis in (0, 1):
        for shift in (-2, -1, 1, 2):
            grown |= np.roll(silhouette, shift, axis=axis)
    h, w = silhouette.shape
    for row, to_640 in zip(recorder.rows, (1.0, 640 / 480)):
        (overlay,) = row.overlays
        px = np.round((overlay.pixels + 0.5) * to_640 - 0.5).astype(int)
        inside = (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0) & (px[:, 1] < h)
        assert inside.all()
        assert grown[px[:, 1], px[:, 0]].mean() > 0.95, row.look
    assert recorder.rows[0].depth_shade.shape == (480, 640) and recorder.rows[1].depth_shade is None
    assert recorder.rows[1].rgb.shape == (360, 480, 3)
    assert paths == [tmp_path / "looks_sheet.png"]  # never ticked: no video
    assert iio.imread(paths[0]).shape[0] > iio.imread(paths[0]).shape[1] / 2  # two rows


def test_a_file_in_the_way_of_the_directory_is_a_clear_error(tmp_path):
    blocker = tmp_path / "taken"
    blocker.write_text("not a directory")
    for directory in (blocker, blocker / "below"):
        with pytest.raises(RecordingError, match="--record") as caught:
            EpisodeRecorder(directory, "ep")
        assert isinstance(caught.value, PsorrError) and str(directory) in str(caught.value)


def test_the_cli_reports_a_bad_record_directory(tmp_path, capsys):
    from sim.cli import main

    blocker = tmp_path / "taken"
    blocker.write_text("")
    assert main(["run", "tasks/demo.yaml", "--poses", "oracle", "--occluder", "off", "--record", str(blocker)]) == 2
    err = capsys.readouterr().err
    assert str(blocker) in err and "Traceback" not in err
