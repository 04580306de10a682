"""Rerun recordings of an episode (sim/recording/rerun_episode.py), read back with Rerun's own chunk reader;
and psorr-sim run --rerun without rerun-sdk. Headless."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim.control.recorder_hooks import combined
from sim.episode import run_episode
from sim.world import WorldConfig, build_world

REPO = Path(__file__).resolve().parents[3]
SEED = 8  # u_channel alone: the person is in view at the first looks, then the pick goes ahead


def _entities(path) -> dict[str, list]:
    from rerun.chunk import RrdReader

    rows: dict[str, list] = {}
    for chunk in RrdReader(path).stream():
        batch = chunk.to_record_batch()
        rows.setdefault(chunk.entity_path, []).extend(
            batch.select([n for n in batch.schema.names if ":" in n or n == "sim_time"]).to_pylist())
    return rows


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    pytest.importorskip("rerun")
    from sim.recording.rerun_episode import RerunEpisodeRecorder, _moving_bodies

    path = tmp_path_factory.mktemp("rerun") / "episode.rrd"
    world = build_world(WorldConfig(workpieces=("u_channel",)), np.random.default_rng(SEED))
    with RerunEpisodeRecorder(path) as recorder:
        result = run_episode(world, np.random.default_rng(SEED), poses="recognized", occluder=True,
                             recorder=recorder)
    return world, recorder, result, _entities(path), [world.model.body(b).name for b in _moving_bodies(world.model)]


def test_every_moving_body_has_its_pose_at_every_logged_step(recorded):
    world, recorder, result, rows, moving = recorded
    assert recorder.steps >= 10 * result.sim_s  # 20 a simulated second
    assert {"arm/gripper", "u_channel", "human/hand"} <= set(moving)
    for body in moving:
        poses = [r for r in rows[f"/cell/bodies/{body}"] if r.get("Transform3D:translation") is not None]
        assert len(poses) == recorder.steps, body
        assert len({r["sim_time"] for r in poses}) == recorder.steps  # each step at its own time


def test_each_visual_geom_is_a_mesh_in_its_body(recorded):
    world, _, _, rows, _ = recorded
    meshes = [p for p, r in rows.items() if any(x.get("Mesh3D:vertex_positions") for x in r)
              and p.startswith("/cell/bodies/")]
    visual = [g for g in range(world.model.ngeom) if world.model.geom_group[g] < 3 and world.model.geom_type[g] != 0]
    assert len(meshes) == len(visual)
    assert "/cell/bodies/u_channel/u_channel_visual" in meshes


def test_looks_grasp_plans_stops_and_the_pick_are_there(recorded):
    _, _, result, rows, _ = recorded
    (pick,) = result.picks
    assert pick.placed
    seen = result.looks - result.occupied_looks
    assert len(rows["/cell/looks/cloud"]) == seen and len(rows["/cell/looks/person"]) == result.occupied_looks
    assert any(p.startswith("/cell/looks/detections/") and p.endswith("_u_channel") for p in rows)
    assert {"/cell/grasp_plans/u_channel/grasp", "/cell/grasp_plans/u_channel/seat"} <= set(rows)
    logs = [text for r in rows["/cell/picks"] for text in r["TextLog:text"]]
    assert logs[-1].startswith("u_channel: placed")
    assert [r["Scalars:scalars"] for r in rows["/cell/picks/grasp_success"]] == [[1.0]]
    assert len(rows.get("/cell/protective_stops", [])) == result.protective_stops


def test_each_look_s_recognition_is_recorded_in_the_camera_frame(recorded):
    _, _, result, rows, _ = recorded
    assert rows["/cell/camera"][0]["Transform3D:translation"] is not None
    seen = result.looks - result.occupied_looks
    assert len(rows["/cell/camera/recognition/table"]) == seen
    assert 1 <= len(rows["/cell/camera/recognition/candidates/round_00"]) <= seen
    # A lone part at rest is found before anything is decomposed (decision 0066), so a look logs its
    # decomposition only when it made one.
    assert len(rows.get("/cell/camera/recognition/decomposition/scene/boxes", [])) <= seen
    assert any(p.startswith("/cell/camera/recognition/detections/") for p in rows)
    assert "/cell/camera/recognition/cloud" not in rows  # the episode's own look logs the cloud


def test_two_recorders_get_every_call():
    calls = []

    class Counting:
        def __getattr__(self, name):
            return lambda *args: calls.append(name)

    both = combined(Counting(), None, Counting())
    both.tick(None, None)
    both.picked(None, None, None)
    assert calls == ["tick", "tick", "picked", "picked"]
    assert combined(None, None) is None


def test_without_rerun_psorr_sim_run_is_one_line_naming_the_extra(tmp_path):
    script = ("import sys; sys.modules['rerun'] = None; from sim.cli import main; "
              f"sys.exit(main(['run', {str(REPO / 'tasks' / 'sweeps' / 'one_part.yaml')!r}, '--poses', 'oracle', "
              "'--occluder', 'off', '--rerun', 'x.rrd']))")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode == 2
    errors = [line for line in out.stderr.splitlines() if "error" in line]
    assert len(errors) == 1 and "pip install 'psorr[viz]'" in errors[0] and "Traceback" not in out.stderr
