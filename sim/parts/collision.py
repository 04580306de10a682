"""Collision hulls for any mesh: CoACD's convex decomposition, run in a child process and cached by the mesh's hash.

MuJoCo takes each collision mesh's convex hull, so a part keeps its cavities (a U-channel's slot, a
tray's inside, a bore) only as several convex pieces. :func:`collision_hulls` derives them for a user's
mesh as ``assets/workpieces/build_collision.py`` does for the catalog, through the same
:func:`sim.parts.coacd_worker.decompose`, but in ``python -m sim.parts.coacd_worker``: CoACD cannot
share a process with Open3D (``std::bad_cast``). The effort scales with the part
(:func:`coacd_settings`; decision record 0055).
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import sim
from psorr.io import read_mesh
from sim.errors import CollisionHullError, SimInputError
from sim.parts.coacd_worker import MISSING_COACD, STALLED, load_mesh
from sim.parts.simplify import simplified

RECORD = "collision.json"
_REPAIR = "repair the mesh (it must be closed) or simplify it (fewer faces)"


@dataclass(frozen=True)
class CollisionParams:
    """CoACD's settings for a part's collision hulls (decision record 0055).

    Attributes:
        concavity: m, how far a hull may stand off the part's surface. CoACD's ``threshold`` is a share of
            the part's largest extent, so it is this over that extent, clipped to [``min_threshold``, 1]:
            0.1 for a 50 mm part, 0.05 for a 100 mm one.
        min_threshold: the finest ``threshold``, which bounds the search's effort on a large part; the
            catalog's (``assets/workpieces/build_collision.py``).
        max_convex_hull: at most this many hulls; CoACD merges the closest ones down to it.
        max_ch_vertex: at most this many vertices a hull (MuJoCo's collision cost grows with them).
        decimate: let CoACD thin each hull down to ``max_ch_vertex``.
        mcts_iterations: CoACD's tree-search iterations per cut (CoACD's default 150).
        mcts_nodes: CoACD's tree-search children per node (CoACD's default 20).
        remesh_resolution: cells across the part's largest extent of CoACD's remeshing (its
            ``preprocess_resolution``), which makes an open mesh closed and closes gaps narrower than a
            cell (1.75 mm of a 70 mm part).
        simplify: the search runs on the part decimated as far as it stays closed and within this share of
            ``concavity`` of the part's surface (:mod:`sim.parts.simplify`; 0 searches the mesh as it is).
        max_rounds: CoACD cuts every piece still too concave once a round; a search needing more rounds is
            slicing one piece ever thinner (narrow gaps do that) and is stopped, and the part remeshed.
        seed: CoACD's seed; equal settings give equal hulls.
        timeout_s: s, the longest a part's decomposition may take, remeshing included (the slowest of 53
            parts measured took 130 s on one busy core).
    """

    concavity: float = 0.005
    min_threshold: float = 0.05
    max_convex_hull: int = 16
    max_ch_vertex: int = 64
    decimate: bool = True
    mcts_iterations: int = 60
    mcts_nodes: int = 10
    remesh_resolution: int = 40
    simplify: float = 0.2
    max_rounds: int = 20
    seed: int = 0
    timeout_s: float = 300.0

    def __post_init__(self):
        if not 0 < self.concavity < 1:
            raise SimInputError(f"concavity must be in metres, in (0, 1), got {self.concavity!r}")
        if not 0 < self.min_threshold <= 1:
            raise SimInputError(f"min_threshold must be in (0, 1] (a share of the part's size), "
                                f"got {self.min_threshold!r}")
        for name in ("max_convex_hull", "max_ch_vertex", "mcts_iterations", "mcts_nodes", "remesh_resolution",
                     "max_rounds"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise SimInputError(f"{name} must be a whole number of at least 1, got {value!r}")
        if not 0 <= self.simplify < 1:
            raise SimInputError(f"simplify must be a share of concavity in [0, 1), got {self.simplify!r}")
        if not self.timeout_s > 0:
            raise SimInputError(f"timeout_s must be a positive number of seconds, got {self.timeout_s!r}")


def coacd_settings(mesh, params: CollisionParams = CollisionParams()) -> dict:
    """The keyword arguments of :func:`coacd.run_coacd` for ``mesh`` (a trimesh.Trimesh in metres).

    An open mesh is remeshed (CoACD cuts closed solids); a closed one is taken as it is, since the
    remeshing costs time and bulges the hulls by up to a cell, unless its search stalls
    (:func:`collision_hulls` then retries it remeshed).
    """
    extent = float(mesh.extents.max())
    return {"threshold": round(min(1.0, max(params.min_threshold, params.concavity / extent)), 4),
            "max_convex_hull": params.max_convex_hull, "max_ch_vertex": params.max_ch_vertex,
            "decimate": params.decimate, "mcts_iterations": params.mcts_iterations, "mcts_nodes": params.mcts_nodes,
            "seed": params.seed, "preprocess_mode": "off" if mesh.is_watertight else "on",
            "preprocess_resolution": params.remesh_resolution}


def collision_hulls(mesh_path: Path, out_dir: Path, params: CollisionParams = CollisionParams()) -> tuple[Path, ...]:
    """The convex collision hulls of the mesh at ``mesh_path``, derived once and cached in ``out_dir``.

    Args:
        mesh_path: an STL (or OBJ, PLY) in metres, in the part's model frame.
        out_dir: this mesh's folder of derived files (the caller's choice, e.g. named by the mesh's hash).
            Gets ``hull_<k>.stl`` (binary STL, metres, largest hull first) and ``collision.json``
            ``{"source_sha256", "settings", "files", "seconds", "coacd_version", "remeshed", "rounds",
            "searched_faces"}``.
        params: CoACD's settings.

    Returns:
        The hull files, largest first. When ``collision.json`` matches the mesh's SHA-256 and the settings
        and its files exist, they are returned without running CoACD.

    Raises:
        CloudFileError: the mesh cannot be read (names the file and the fix).
        CollisionHullError: coacd is not installed, or CoACD failed or took longer than ``params.timeout_s``.
    """
    mesh_path, out_dir = Path(mesh_path), Path(out_dir)
    read_mesh(mesh_path)  # refuses a file that is no mesh, naming it and the fix
    mesh = load_mesh(mesh_path)
    source_sha256 = hashlib.sha256(mesh_path.read_bytes()).hexdigest()
    settings = {**coacd_settings(mesh, params), "max_rounds": params.max_rounds,
                "simplify_tolerance": round(params.simplify * params.concavity, 6)}
    cached = _cached(out_dir, source_sha256, settings)
    if cached is not None:
        return cached
    if importlib.util.find_spec("coacd") is None:
        raise _missing_coacd(mesh_path)
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", dir=out_dir.parent))
    try:
        start = time.perf_counter()
        search_path, searched_faces = _search_mesh(mesh, mesh_path, scratch, settings["simplify_tolerance"])
        try:
            try:
                summary = _decompose(mesh_path, search_path, scratch, settings, start + params.timeout_s)
            except CollisionHullError:
                if search_path == mesh_path:
                    raise
                # CoACD failing on the simplified copy, the part is searched as it is.
                search_path, searched_faces = mesh_path, len(mesh.faces)
                summary = _decompose(mesh_path, mesh_path, scratch, settings, start + params.timeout_s)
        except subprocess.TimeoutExpired:
            raise CollisionHullError(mesh_path, f"CoACD's convex decomposition took longer than {params.timeout_s:g} s "
                                     "and was stopped", f"{_REPAIR}, or raise CollisionParams.timeout_s") from None
        record = {"source_sha256": source_sha256, "settings": settings, "files": summary["files"],
                  "seconds": round(time.perf_counter() - start, 2), "coacd_version": summary["coacd_version"],
                  "remeshed": summary["remeshed"], "rounds": summary["rounds"], "searched_faces": searched_faces}
        (scratch / RECORD).write_text(json.dumps(record, indent=1) + "\n")
        _move_into_place(scratch, out_dir, summary["files"])
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return tuple(out_dir / file for file in summary["files"])


def _cached(out_dir: Path, source_sha256: str, settings: dict) -> tuple[Path, ...] | None:
    """The files ``out_dir/collision.json`` lists, if it was made from this source with these settings."""
    try:
        record = json.loads((out_dir / RECORD).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("source_sha256") != source_sha256 \
            or record.get("settings") != json.loads(json.dumps(settings)) or not record.get("files"):
        return None
    files = tuple(out_dir / file for file in record["files"])
    return files if all(path.is_file() for path in files) else None


def _search_mesh(mesh, mesh_path: Path, scratch: Path, tolerance: float) -> tuple[Path, int]:
    """The mesh CoACD searches: ``mesh`` simplified within ``tolerance`` m, written into ``scratch``, or the
    file as it is when it is open or no decimation keeps within the tolerance; and its faces."""
    fewer = simplified(mesh, tolerance) if tolerance > 0 else None
    if fewer is None:
        return mesh_path, len(mesh.faces)
    path = scratch / "search.stl"
    path.write_bytes(fewer.export(file_type="stl"))
    return path, len(fewer.faces)


def _decompose(mesh_path: Path, search_path: Path, scratch: Path, settings: dict, deadline: float) -> dict:
    """Run the worker on ``search_path`` (``mesh_path``'s mesh, or its simplified copy), into ``scratch``;
    remeshed once more if its search stalls. The worker's summary plus ``remeshed``."""
    coacd_args = {key: value for key, value in settings.items() if key not in ("max_rounds", "simplify_tolerance")}
    status, summary = _run_worker(mesh_path, search_path, scratch, coacd_args, settings["max_rounds"], deadline)
    if status == STALLED and coacd_args["preprocess_mode"] == "off":
        coacd_args["preprocess_mode"] = "on"  # closes the narrow gaps the search slices forever
        status, summary = _run_worker(mesh_path, search_path, scratch, coacd_args, settings["max_rounds"], deadline)
    if status == STALLED:
        raise CollisionHullError(mesh_path, f"CoACD's search did not settle within {settings['max_rounds']} rounds "
                                 "of cuts, even remeshed", f"{_REPAIR}, or raise CollisionParams.max_rounds")
    return {**summary, "remeshed": coacd_args["preprocess_mode"] == "on"}


def _run_worker(mesh_path: Path, search_path: Path, scratch: Path, coacd_args: dict, max_rounds: int,
                deadline: float):
    """Run ``python -m sim.parts.coacd_worker`` on ``search_path`` into ``scratch``: (0, its summary) or (STALLED,
    None). Raises CollisionHullError (naming ``mesh_path``, the user's file) if it failed,
    subprocess.TimeoutExpired at the deadline (it is killed)."""
    command = [sys.executable, "-m", "sim.parts.coacd_worker", str(search_path), str(scratch), json.dumps(coacd_args),
               str(max_rounds)]
    # The child must import this very sim, installed or not.
    root = str(Path(sim.__file__).resolve().parent.parent)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")]))}
    timeout_s = max(0.0, deadline - time.perf_counter())
    done = subprocess.run(command, capture_output=True, text=True, timeout=timeout_s, env=env)
    if done.returncode == MISSING_COACD:
        raise _missing_coacd(mesh_path)
    if done.returncode == STALLED:
        return STALLED, None
    if done.returncode != 0:
        lines = done.stderr.strip().splitlines()
        reason = lines[-1] if lines else f"the process ended with status {done.returncode} and said nothing"
        raise CollisionHullError(mesh_path, f"CoACD's convex decomposition failed: {reason}", _REPAIR)
    return 0, json.loads(done.stdout.strip().splitlines()[-1])


def _move_into_place(scratch: Path, out_dir: Path, files: list[str]) -> None:
    """Move the hulls from ``scratch`` into ``out_dir``, the record last: until it is there, the folder is
    no cache, so an interrupted run leaves none half written."""
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / RECORD).unlink(missing_ok=True)
    for old in out_dir.glob("hull_*.stl"):
        old.unlink()
    for file in [*files, RECORD]:
        os.replace(scratch / file, out_dir / file)


def _missing_coacd(mesh_path: Path) -> CollisionHullError:
    return CollisionHullError(mesh_path, "its collision hulls need CoACD, which is not installed",
                              "pip install coacd")
