"""CoACD's convex decomposition of one mesh, in a process of its own: ``python -m sim.parts.coacd_worker``.

CoACD and Open3D crash when they share a process (``std::bad_cast``), and psorr imports Open3D. So this
module imports numpy, scipy, trimesh and coacd only (``import sim`` itself loads gymnasium, no more), and
coacd only inside the functions that run it: the sim's tests import every module of ``sim``.
:mod:`sim.parts.collision` runs it as a child process; ``assets/workpieces/build_collision.py`` calls
:func:`decompose` for the catalog, so both take the same hulls from the same code.

Command line::

    python -m sim.parts.coacd_worker MESH OUT_DIR SETTINGS_JSON MAX_ROUNDS

MESH is an STL in metres; SETTINGS_JSON a JSON object of :func:`coacd.run_coacd`'s keyword arguments.
Writes ``OUT_DIR/hull_<k>.stl`` (binary STL, metres, largest hull first) and prints one JSON line on
stdout: ``{"files": [...], "seconds": s, "rounds": n, "coacd_version": "..."}``. CoACD cuts every
piece still too concave once a round; a search that needs more than MAX_ROUNDS rounds is slicing one piece
ever thinner (narrow gaps do that) and is stopped. Exit status: 0 done; 3 coacd is not installed;
4 stopped after MAX_ROUNDS rounds; 1 anything else. Each failure's reason is the last line of stderr.
"""

from __future__ import annotations

import json
import os
import re
import sys
import threading
import time
from importlib import metadata
from pathlib import Path

import numpy as np
import trimesh

MISSING_COACD = 3
"""Exit status when coacd cannot be imported, so the caller can name the fix rather than a traceback."""
STALLED = 4
"""Exit status when CoACD's search needed more than MAX_ROUNDS rounds."""
_ROUND = re.compile(rb"iter (\d+) ----")


def load_mesh(path: Path) -> trimesh.Trimesh:
    """The mesh file at ``path`` with only its equal vertices merged (to 1e-12). trimesh's default merges
    vertices closer than 1e-8, which in metres joins a CAD export's near-duplicate corners and can open a
    closed mesh (one of 45 printed parts, converted from millimetres)."""
    mesh = trimesh.load(path, force="mesh", process=False)
    mesh.merge_vertices(digits_vertex=12)
    return mesh


def decompose(mesh: trimesh.Trimesh, settings: dict, log_level: str = "error") -> list[trimesh.Trimesh]:
    """CoACD's convex hulls of ``mesh`` (metres), largest first, each clamped to the mesh's bounding box.

    Args:
        mesh: the part, in metres, in its model frame.
        settings: keyword arguments of :func:`coacd.run_coacd` (threshold, max_convex_hull, preprocess_mode, ...).
        log_level: CoACD's log level; ``"info"`` logs each round of cuts to stdout.

    Returns:
        The hulls as closed convex meshes (metres), sorted by volume, then by centroid, so that equal
        settings give equal files.
    """
    import coacd

    coacd.set_log_level(log_level)
    parts = coacd.run_coacd(coacd.Mesh(mesh.vertices, mesh.faces), **settings)
    lo, hi = mesh.bounds
    # A remeshed (preprocessed) part bulges up to a voxel; clamping keeps every hull within the part's
    # box, so a part's resting face stays where its mesh has it.
    hulls = [trimesh.convex.convex_hull(np.clip(np.asarray(vertices, dtype=np.float64), lo, hi))
             for vertices, _ in parts]
    hulls.sort(key=lambda h: (-h.volume, tuple(np.round(h.centroid, 6))))
    return hulls


def write_hulls(mesh_path: Path, out_dir: Path, settings: dict, max_rounds: int) -> dict:
    """Decompose the STL at ``mesh_path`` (metres) into ``out_dir/hull_<k>.stl``, stopping the process with
    STALLED if CoACD needs more than ``max_rounds`` rounds; return the run's summary (see the module's docstring)."""
    mesh = load_mesh(mesh_path)
    start = time.perf_counter()
    with _RoundWatch(max_rounds) as watch:
        hulls = decompose(mesh, settings, log_level="info")
    seconds = time.perf_counter() - start
    if not hulls:
        raise RuntimeError("CoACD returned no hulls")
    files = []
    for k, hull in enumerate(hulls):
        path = out_dir / f"hull_{k}.stl"
        path.write_bytes(hull.export(file_type="stl"))
        files.append(path.name)
    return {"files": files, "seconds": round(seconds, 3), "rounds": watch.rounds,
            "coacd_version": metadata.version("coacd")}


class _RoundWatch:
    """Reads CoACD's log, which it writes to file descriptor 1, through a pipe while it runs, and ends the
    process once a round numbered ``max_rounds`` starts. CoACD's call releases the GIL, so the reading
    thread runs alongside it."""

    def __init__(self, max_rounds: int):
        self.max_rounds, self.rounds = max_rounds, 0

    def __enter__(self):
        sys.stdout.flush()
        self._stdout = os.dup(1)
        read_end, write_end = os.pipe()
        os.dup2(write_end, 1)
        os.close(write_end)
        self._thread = threading.Thread(target=self._read, args=(read_end,), daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc):
        os.dup2(self._stdout, 1)  # closes the pipe's last write end: the reader sees its end
        os.close(self._stdout)
        self._thread.join(timeout=5)

    def _read(self, fd: int) -> None:
        with os.fdopen(fd, "rb") as log:
            for line in log:
                match = _ROUND.search(line)
                if match:
                    self.rounds = int(match.group(1)) + 1
                    if self.rounds > self.max_rounds:
                        print(f"CoACD's search did not settle within {self.max_rounds} rounds of cuts",
                              file=sys.stderr, flush=True)
                        os._exit(STALLED)


def main(argv: list[str] | None = None) -> int:
    """The command line (see the module's docstring); returns the exit status."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 4:
        print("usage: python -m sim.parts.coacd_worker MESH OUT_DIR SETTINGS_JSON MAX_ROUNDS", file=sys.stderr)
        return 1
    try:
        import coacd  # noqa: F401 - only whether it is there
    except ImportError as exc:
        print(f"coacd cannot be imported: {exc}", file=sys.stderr)
        return MISSING_COACD
    try:
        summary = write_hulls(Path(args[0]), Path(args[1]), json.loads(args[2]), int(args[3]))
    except Exception as exc:  # CoACD, trimesh and the file system raise many types; the caller reports the last line
        print(f"{type(exc).__name__}: {exc}".replace("\n", " "), file=sys.stderr)
        return 1
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
