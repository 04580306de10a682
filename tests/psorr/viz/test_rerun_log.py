"""Rerun recordings of a recognition and a decomposition (psorr/viz/rerun_log.py), read back with Rerun's own
chunk reader; and the one-line error when rerun-sdk is missing."""

import json
import subprocess
import sys

import numpy as np
import pytest

from psorr.errors import InvalidInputError, MissingExtraError
from psorr.io.clouds import write_cloud
from psorr.library.models import ModelLibrary
from psorr.recognize import Recognizer
from psorr.synthetic import primitive_scenes as synthetic
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.viz import RecognitionObserver, RerunLogger

PARTS = ("chassis", "flanged_hub")


def _entities(path) -> dict[str, list]:
    """Every entity of the recording at ``path`` and its rows (pyarrow dicts, one per log call)."""
    from rerun.chunk import RrdReader

    rows: dict[str, list] = {}
    for chunk in RrdReader(path).stream():
        batch = chunk.to_record_batch()
        components = batch.select([n for n in batch.schema.names if ":" in n])  # not the row ids and log times
        rows.setdefault(chunk.entity_path, []).extend(components.to_pylist())
    return rows


def _count(rows: list[dict], column: str) -> int:
    """Instances of ``column`` (such as ``Boxes3D:centers``) over ``rows``."""
    return sum(len(r[column]) for r in rows if r.get(column) is not None)


@pytest.fixture(scope="module")
def scene_and_library(tmp_path_factory):
    pytest.importorskip("rerun")
    import os

    os.environ["PSORR_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    catalog = load_catalog()
    scene = workpiece_scene(np.random.default_rng(3), {n: catalog[n].load_mesh() for n in PARTS}, list(PARTS))
    return scene, ModelLibrary.from_meshes([catalog[n].mesh_path for n in PARTS])


class CountingLogger(RerunLogger):
    """A RerunLogger that also keeps the primitives and edges of each decomposition it records."""

    def __init__(self, path):
        super().__init__(path)
        self.shapes = {}

    def decomposition(self, name, cloud, scene):
        super().decomposition(name, cloud, scene)
        if scene is not None:
            self.shapes[name] = (len(scene.graph.primitives), len(scene.graph.edges))


def test_a_recording_holds_each_stage_and_changes_no_detection(scene_and_library, tmp_path):
    scene, library = scene_and_library
    recognizer = Recognizer(library)
    plain = recognizer.recognize(scene.cloud, np.random.default_rng(0))
    with CountingLogger(tmp_path / "scene.rrd") as seen:
        recorded = recognizer.recognize(scene.cloud, np.random.default_rng(0), observer=seen)
    assert [(d.model, d.T_cloud_model.tolist()) for d in recorded.detections] == \
        [(d.model, d.T_cloud_model.tolist()) for d in plain.detections]
    assert sorted(d.model for d in plain.detections) == sorted(PARTS)

    rows = _entities(tmp_path / "scene.rrd")
    meshes = [p for p in rows if p.startswith("/recognition/detections/") and p.endswith("/mesh")]
    assert len(meshes) == len(plain.detections)  # one posed mesh per detection
    for path in meshes:
        (row,) = rows[path]
        assert row["Transform3D:translation"] is not None and len(row["Mesh3D:triangle_indices"]) > 0
        assert _count(rows[path.replace("/mesh", "/support")], "Points3D:positions") > 100
    for name, (primitives, edges) in seen.shapes.items():  # one box per primitive, one line per edge
        assert _count(rows[f"/recognition/decomposition/{name}/boxes"], "Boxes3D:centers") == primitives
        assert _count(rows[f"/recognition/decomposition/{name}/edges"], "LineStrips3D:strips") == edges
    rounds = [p for p in rows if p.startswith("/recognition/candidates/round_")]
    assert rounds and all(_count(rows[p], "Boxes3D:labels") > 0 for p in rounds)
    reasons = [label for r in rows["/recognition/rejected"] for label in r["Points3D:labels"]]
    assert reasons and all(": " in label for label in reasons)  # "model: why it was turned down"
    assert {"/recognition/cloud", "/recognition/table", "/recognition/time_ms/total"} <= set(rows)


def test_psorr_decompose_records_one_box_per_primitive(tmp_path):
    pytest.importorskip("rerun")
    write_cloud(tmp_path / "scene.pcd", synthetic.box_on_table(np.random.default_rng(0)).cloud)
    out = subprocess.run([sys.executable, "-m", "psorr.cli", "decompose", str(tmp_path / "scene.pcd"), "--json",
                          "--rerun", str(tmp_path / "d.rrd")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    record = json.loads(out.stdout)
    rows = _entities(tmp_path / "d.rrd")
    assert _count(rows["/recognition/decomposition/scene/boxes"], "Boxes3D:centers") == len(record["primitives"])
    assert _count(rows["/recognition/decomposition/scene/edges"], "LineStrips3D:strips") == len(record["edges"])


def test_without_rerun_the_option_is_one_line_naming_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "rerun", None)  # import rerun now raises ImportError
    with pytest.raises(MissingExtraError, match=r"pip install 'psorr\[viz\]'"):
        RerunLogger(tmp_path / "x.rrd")
    write_cloud(tmp_path / "scene.pcd", synthetic.box_on_table(np.random.default_rng(0)).cloud)
    script = ("import sys; sys.modules['rerun'] = None; from psorr.cli import main; "
              f"sys.exit(main(['decompose', {str(tmp_path / 'scene.pcd')!r}, '--rerun', 'x.rrd']))")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert out.returncode == 2 and out.stderr.count("\n") == 1
    assert "pip install 'psorr[viz]'" in out.stderr and "Traceback" not in out.stderr


def test_an_observer_that_is_not_one_is_refused(scene_and_library):
    scene, library = scene_and_library
    with pytest.raises(InvalidInputError, match="must be a psorr.viz.RecognitionObserver"):
        Recognizer(library).recognize(scene.cloud, observer=print)


def test_stages_report_nothing_after_the_recognition(scene_and_library):
    from psorr.viz.observer import observer, watched

    assert not watched() and type(observer()) is RecognitionObserver


def _kill_processes_naming(text: str) -> None:
    """Stop every process whose command line holds ``text`` (the spawned viewer detaches from its parent)."""
    import os
    import signal
    from pathlib import Path

    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            if text in cmdline.read_bytes().decode(errors="replace"):
                os.kill(int(cmdline.parent.name), signal.SIGTERM)
        except (OSError, ValueError):
            pass


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="stands a shell script in for the viewer")
def test_rerun_without_a_file_streams_to_a_viewer_it_spawns(tmp_path):
    """``--rerun`` alone spawns ``rerun`` from PATH and streams to it. The viewer here is Rerun's own command
    with ``--save`` added, so that what it receives is written to a file instead of drawn on a display."""
    import os
    import time

    pytest.importorskip("rerun")
    received = tmp_path / "received.rrd"
    viewer = tmp_path / "bin" / "rerun"
    viewer.parent.mkdir()
    # Its output to /dev/null: it outlives the command, whose pipes it would otherwise hold open.
    viewer.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m rerun_cli "$@" --save "{received}" '
                      '</dev/null >/dev/null 2>&1\n')
    viewer.chmod(0o755)
    write_cloud(tmp_path / "scene.pcd", synthetic.box_on_table(np.random.default_rng(0)).cloud)
    env = {**os.environ, "PATH": f"{viewer.parent}{os.pathsep}{os.environ['PATH']}"}
    try:
        out = subprocess.run([sys.executable, "-m", "psorr.cli", "decompose", str(tmp_path / "scene.pcd"), "--json",
                              "--rerun"], capture_output=True, text=True, timeout=120, env=env)
        assert out.returncode == 0, out.stderr
        primitives = len(json.loads(out.stdout)["primitives"])
        boxes = None
        for _ in range(40):  # the viewer writes what it has received as it arrives
            if received.exists():
                rows = _entities(received)
                if "/recognition/decomposition/scene/boxes" in rows:
                    boxes = _count(rows["/recognition/decomposition/scene/boxes"], "Boxes3D:centers")
                    break
            time.sleep(0.25)
        assert boxes == primitives
    finally:
        _kill_processes_naming(str(received))


def test_rerun_without_a_file_and_no_viewer_is_one_line_naming_the_fix(tmp_path):
    import os

    pytest.importorskip("rerun")
    write_cloud(tmp_path / "scene.pcd", synthetic.box_on_table(np.random.default_rng(0)).cloud)
    env = {**os.environ, "PATH": str(tmp_path)}  # no `rerun` to spawn
    out = subprocess.run([sys.executable, "-m", "psorr.cli", "decompose", str(tmp_path / "scene.pcd"), "--rerun"],
                         capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "cannot start the Rerun viewer" in out.stderr and "--rerun OUT.rrd" in out.stderr
