"""Running a sweep: each episode in a worker (a local process pool, or Ray tasks), its rows written to Parquet
as it finishes, so that a sweep stopped and started again resumes where it left off.

Each finished episode leaves ``OUT/rows/<id>.episode.parquet`` (one row) and ``<id>.picks.parquet`` (one
row a pick), written whole under a temporary name and then moved. An episode whose row is there is not
run again. At the end ``OUT/episodes.parquet`` and ``OUT/picks.parquet`` gather every row, in the grid's
order. Models and grasps are trained or derived once per machine and cached on disk (``PSORR_CACHE``), so a
worker after the first on a machine finds them there.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from pathlib import Path

from sim.sweeps.spec import EpisodeSpec, Sweep

EPISODE_COLUMNS = ("id", "task", "seed", "poses", "camera_height", "resolution", "occluder", "noise", "method",
                   "picks", "grasped", "placed", "grasp_success_rate", "place_success_rate", "wall_s", "sim_s", "looks")
# OpenMP (Open3D), BLAS (numpy), numba, and llvmpipe, the software OpenGL MuJoCo renders with headless.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS", "LP_NUM_THREADS")
PICK_COLUMNS = ("id", "part", "grasp", "grasped", "placed", "pose_error_mm", "rot_error_deg", "note")


def run_episode_rows(spec: EpisodeSpec) -> tuple[dict, list[dict]]:
    """Run one episode of the grid; its episode row and pick rows (plain values, for Parquet)."""
    import numpy as np

    from sim.episode import run_episode
    from sim.world import build_world

    rng = np.random.default_rng([spec.seed, 0])
    config = spec.world_config()
    world = build_world(config, rng)
    result = run_episode(world, rng, poses=spec.poses, occluder=spec.occluder, perception=spec.perception)
    picks = result.picks
    episode = {"id": spec.id, "task": Path(spec.task).name, "seed": spec.seed, "poses": spec.poses,
               "camera_height": float(config.camera_height), "resolution": spec.resolution,
               "occluder": spec.occluder, "noise": spec.noise, "method": spec.method, "picks": len(picks),
               "grasped": sum(p.grasped for p in picks), "placed": sum(p.placed for p in picks),
               "grasp_success_rate": sum(p.grasped for p in picks) / len(picks) if picks else 0.0,
               "place_success_rate": sum(p.placed for p in picks) / len(picks) if picks else 0.0,
               "wall_s": result.wall_s, "sim_s": result.sim_s, "looks": result.looks}
    rows = [{"id": spec.id, "part": p.part, "grasp": p.grasp_name, "grasped": p.grasped, "placed": p.placed,
             "pose_error_mm": float(p.pose_error_mm), "rot_error_deg": float(p.rot_error_deg), "note": p.note}
            for p in picks]
    return episode, rows


def pending(sweep: Sweep, out: Path) -> list[EpisodeSpec]:
    """The grid's episodes without a row in ``out`` yet, in grid order."""
    return [spec for spec in sweep.episodes if not (out / "rows" / f"{spec.id}.episode.parquet").is_file()]


def save_rows(out: Path, episode: dict, picks: list[dict]) -> None:
    """One finished episode's rows, the picks first and the episode row (which marks it done) last."""
    _write(out / "rows" / f"{episode['id']}.picks.parquet", picks, PICK_COLUMNS)
    _write(out / "rows" / f"{episode['id']}.episode.parquet", [episode], EPISODE_COLUMNS)


def _write(path: Path, rows: list[dict], columns: tuple[str, ...]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    path.parent.mkdir(parents=True, exist_ok=True)
    table = pa.Table.from_pylist(rows, schema=_schema(columns)) if rows else _schema(columns).empty_table()
    tmp = path.with_name(f"{path.name}.{uuid.uuid4().hex}.tmp")
    pq.write_table(table, tmp)
    os.replace(tmp, path)


def _schema(columns: tuple[str, ...]):
    import pyarrow as pa

    types = {"seed": pa.int64(), "picks": pa.int64(), "grasped": pa.int64(), "placed": pa.int64(),
             "looks": pa.int64(), "occluder": pa.bool_(), "camera_height": pa.float64(), "noise": pa.float64(),
             "wall_s": pa.float64(),
             "sim_s": pa.float64(), "grasp_success_rate": pa.float64(), "place_success_rate": pa.float64(),
             "pose_error_mm": pa.float64(), "rot_error_deg": pa.float64()}
    if columns == PICK_COLUMNS:
        types.update({"grasped": pa.bool_(), "placed": pa.bool_()})
    return pa.schema([(c, types.get(c, pa.string())) for c in columns])


def gather(sweep: Sweep, out: Path) -> tuple[Path, Path]:
    """Write ``out/episodes.parquet`` and ``out/picks.parquet`` from every finished episode, in grid order."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    paths = {}
    for kind, columns in (("episode", EPISODE_COLUMNS), ("picks", PICK_COLUMNS)):
        parts = [out / "rows" / f"{s.id}.{kind}.parquet" for s in sweep.episodes]
        tables = [pq.read_table(p) for p in parts if p.is_file()]
        table = pa.concat_tables(tables) if tables else _schema(columns).empty_table()
        paths[kind] = out / ("episodes.parquet" if kind == "episode" else "picks.parquet")
        pq.write_table(table, paths[kind])
    return paths["episode"], paths["picks"]


def run_local(specs: Iterable[EpisodeSpec], out: Path, workers: int,
              done: Callable[[dict], None] = lambda row: None, pool: bool | None = None) -> None:
    """Run ``specs`` on a pool of ``workers`` processes, saving each as it finishes; with ``pool`` None, one
    worker runs in this process."""
    specs = list(specs)
    if workers == 1 and not pool:
        for spec in specs:
            episode, picks = run_episode_rows(spec)
            save_rows(out, episode, picks)
            done(episode)
        return
    # Each worker a fresh interpreter (spawn): MuJoCo's renderer and Open3D do not survive a fork.
    import multiprocessing

    with one_thread_each(), ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as executor:
        futures = [executor.submit(run_episode_rows, spec) for spec in specs]
        for future in as_completed(futures):
            episode, picks = future.result()
            save_rows(out, episode, picks)
            done(episode)


@contextmanager
def one_thread_each() -> Iterator[None]:
    """While open, processes started from this one keep their numerical libraries and software renderer to
    one thread each: with as many workers as cores, more threads only contend for the same cores. It is set
    in the environment they inherit, since a worker loads numpy, Open3D and MuJoCo (which read their thread
    counts as they load) while it unpickles its first task, before any initializer of its own could run."""
    before = {name: os.environ.get(name) for name in THREAD_VARIABLES}
    os.environ.update(dict.fromkeys(THREAD_VARIABLES, "1"))
    try:
        yield
    finally:
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def run_ray(specs: Iterable[EpisodeSpec], out: Path, address: str | None,
            done: Callable[[dict], None] = lambda row: None, num_cpus: int | None = None) -> None:
    """Run ``specs`` as Ray tasks, one an episode: on a local Ray instance (``address`` None), or on the
    cluster at ``address``. Rows are saved here, by the driver, as each task finishes."""
    try:
        import ray
    except ImportError:
        from sim.errors import SimInputError

        raise SimInputError("--ray needs Ray, which is not installed: pip install 'psorr[ray]' (or run the sweep "
                            "without --ray, on a local process pool)") from None
    started = not ray.is_initialized()
    if started:
        ray.init(address=address, num_cpus=num_cpus if address is None else None, include_dashboard=False,
                 log_to_driver=False)
    try:
        threads = dict.fromkeys(THREAD_VARIABLES, "1")
        remote = ray.remote(num_cpus=1, runtime_env={"env_vars": threads})(run_episode_rows)
        waiting = [remote.remote(spec) for spec in specs]
        while waiting:
            ready, waiting = ray.wait(waiting, num_returns=1)
            episode, picks = ray.get(ready[0])
            save_rows(out, episode, picks)
            done(episode)
    finally:
        if started:
            ray.shutdown()
