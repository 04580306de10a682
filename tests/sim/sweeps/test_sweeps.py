"""Sweeps (sim/sweeps): the grid, Parquet rows on a local pool and on Ray alike, and resuming. Headless."""

from pathlib import Path

import pyarrow.parquet as pq
import pytest

from sim.cli import main
from sim.errors import TaskFileError
from sim.sweeps import gather, load_sweep, pending, run_local, run_ray
from sim.sweeps.run import THREAD_VARIABLES, one_thread_each

REPO = Path(__file__).resolve().parents[3]
SWEEP = ("tasks: [{task}]\nseeds: 2\nposes: [oracle]\noccluder: [true, false]\n")


@pytest.fixture
def sweep_file(tmp_path):
    path = tmp_path / "sweep.yaml"
    path.write_text(SWEEP.format(task=REPO / "tasks" / "sweeps" / "one_part.yaml"))
    return path


def _rows(path: Path) -> list[dict]:
    return [{k: v for k, v in r.items() if k != "wall_s"} for r in pq.read_table(path).to_pylist()]


def test_the_grid_is_every_combination_and_the_smoke_sweep_has_four():
    assert len(load_sweep(REPO / "tasks" / "sweeps" / "smoke.yaml").episodes) == 4


def test_noise_and_method_are_swept_into_each_episodes_looks(tmp_path):
    path = tmp_path / "sweep.yaml"
    path.write_text(f"tasks: [{REPO / 'tasks' / 'sweeps' / 'one_part.yaml'}]\nnoise: [0.5, 2]\nmethod: [psorr, orr]\n")
    sweep = load_sweep(path)
    assert sweep.swept == ("noise", "method") and len(sweep.episodes) == 4
    looks = {(s.perception.noise_scale, s.perception.method) for s in sweep.episodes}
    assert looks == {(0.5, "psorr"), (0.5, "orr"), (2.0, "psorr"), (2.0, "orr")}
    assert len({s.id for s in sweep.episodes}) == 4


@pytest.mark.parametrize(("text", "words"), [
    ("tasks: [x.yaml]\nspeed: 3\n", "line 2: unknown key 'speed'"),
    ("tasks: [{task}]\nseeds: -1\n", "line 2: seeds must be a count"),
    ("tasks: [{task}]\nposes: [guessed]\n", "line 2: poses must be among recognized, oracle"),
    ("tasks: [{task}]\nresolution: [640x400]\n", "line 2: resolution must be WIDTHxHEIGHT"),
    ("tasks: [{task}]\ncamera_height: [2.0]\n", "line 2: camera_height must be metres in [0.6, 1.0]"),
    ("tasks: [{task}]\nnoise: [1, -2]\n", "line 2: noise must be a multiple of the Kinect v1's depth noise"),
    ("tasks: [{task}]\nmethod: [psorr, ppf]\n", "line 2: method must be among psorr"),
])
def test_each_bad_key_is_named_with_its_line(tmp_path, text, words):
    path = tmp_path / "sweep.yaml"
    path.write_text(text.format(task=REPO / "tasks" / "sweeps" / "one_part.yaml"))
    with pytest.raises(TaskFileError, match=words.replace("[", r"\[").replace("]", r"\]")):
        load_sweep(path)


def test_the_local_pool_and_ray_give_the_same_rows(sweep_file, tmp_path):
    ray = pytest.importorskip("ray")
    sweep = load_sweep(sweep_file)
    run_local(sweep.episodes, tmp_path / "local", workers=2)
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        run_ray(sweep.episodes, tmp_path / "ray", address=None)
    finally:
        ray.shutdown()
    local, on_ray = (gather(sweep, tmp_path / name) for name in ("local", "ray"))
    assert len(_rows(local[0])) == 4 and _rows(local[0]) == _rows(on_ray[0])
    assert _rows(local[1]) == _rows(on_ray[1]) and len(_rows(local[1])) == 4  # one pick an episode


def test_a_stopped_sweep_resumes_without_repeating_or_losing_an_episode(sweep_file, tmp_path, capsys):
    sweep, out = load_sweep(sweep_file), tmp_path / "out"
    run_local(sweep.episodes[:2], out, workers=1)  # stopped halfway
    first = {p.name: p.stat().st_mtime_ns for p in (out / "rows").glob("*.parquet")}
    assert len(pending(sweep, out)) == 2
    assert main(["sweep", str(sweep_file), "--out", str(out), "--workers", "1"]) == 0
    assert "poses" not in capsys.readouterr().out.splitlines()[1]  # occluder is the swept variable
    rows = pq.read_table(out / "episodes.parquet").to_pylist()
    assert [r["id"] for r in rows] == [s.id for s in sweep.episodes]
    assert all((out / "rows" / name).stat().st_mtime_ns == t for name, t in first.items())  # not run again
    assert (out / "grasp_success.png").is_file()


def _thread_counts_at_start() -> dict:
    import os

    return {name: os.environ.get(name) for name in THREAD_VARIABLES}


def test_pool_workers_start_with_one_thread_each_and_this_process_keeps_its_own(monkeypatch):
    """A worker's libraries read their thread counts as they load, before any initializer could run, so the
    counts must already be in the environment the worker starts with; this process's are put back."""
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor

    monkeypatch.setenv("OMP_NUM_THREADS", "7")
    monkeypatch.delenv("LP_NUM_THREADS", raising=False)
    with one_thread_each(), ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        seen = pool.submit(_thread_counts_at_start).result()
    assert seen == dict.fromkeys(THREAD_VARIABLES, "1")
    assert os.environ["OMP_NUM_THREADS"] == "7" and "LP_NUM_THREADS" not in os.environ
