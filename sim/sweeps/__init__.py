"""Sweeps: a grid of seeded episodes (tasks x seeds x pose sources x camera), run on a local process pool or
on Ray, with one Parquet row per episode and per pick, resumable (``psorr-sim sweep``)."""

from sim.sweeps.run import gather, pending, run_episode_rows, run_local, run_ray
from sim.sweeps.spec import EpisodeSpec, Sweep, load_sweep

__all__ = ["EpisodeSpec", "Sweep", "gather", "load_sweep", "pending", "run_episode_rows", "run_local", "run_ray"]
