"""Open3D calls whose results depend on how its threads are scheduled, run on one thread.

Open3D sums ICP's normal equations across threads in whatever order they finish, and its
multi-threaded ``segment_plane`` draws RANSAC samples from one generator without a lock, so on a
busy machine the same seed gives another plane (2 distinct planes in 30 calls on a scene of the
peers' set with both cores loaded, as of Open3D 0.20). The last bits of a pose, and everything
a seeded episode does after it, would then change from run to run.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import open3d as o3d


@contextmanager
def limited_threads(n: int) -> Iterator[None]:
    """Run the body with Open3D limited to ``n`` >= 1 threads; the previous limit is restored after."""
    before = o3d.utility.get_max_threads()
    o3d.utility.set_max_threads(n)
    try:
        yield
    finally:
        o3d.utility.set_max_threads(before)


def single_threaded():
    """Run the body with Open3D limited to one thread (a context manager): seeds repeat exactly."""
    return limited_threads(1)
