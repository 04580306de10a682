"""Collision hulls of any mesh (sim/parts/collision.py): CoACD in a child process, cached by the mesh's hash.

coacd is never imported here: this process holds Open3D, and the two crash together (std::bad_cast).
"""

import importlib.util
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull

from psorr.errors import CloudFileError
from sim.errors import CollisionHullError, SimError, SimInputError
from sim.parts.coacd_worker import STALLED
from sim.parts.collision import CollisionParams, coacd_settings, collision_hulls

needs_coacd = pytest.mark.skipif(importlib.util.find_spec("coacd") is None, reason="coacd is not installed")

WIDTH, HEIGHT, WALL, DEPTH = 0.06, 0.04, 0.01, 0.02
"""The U's outline (m): WIDTH along x, HEIGHT along y, walls WALL thick, extruded DEPTH along z."""


def _u_profile() -> trimesh.Trimesh:
    """A closed U-shaped solid: a base and two walls, the slot between them open towards +y."""
    w, h, t = WIDTH, HEIGHT, WALL
    outline = np.array([(0, 0), (w, 0), (w, t), (w, h), (w - t, h), (w - t, t), (t, t), (t, h), (0, h), (0, t)])
    triangles = np.array([(0, 1, 2), (0, 2, 5), (0, 5, 6), (0, 6, 9),  # the base, through the walls' feet
                          (5, 2, 3), (5, 3, 4), (9, 6, 7), (9, 7, 8)])  # the two walls
    mesh = trimesh.creation.extrude_triangulation(outline, triangles, DEPTH)
    assert mesh.is_watertight and mesh.volume == pytest.approx((w * t + 2 * t * (h - t)) * DEPTH)
    return mesh


def _in_u(points: np.ndarray) -> np.ndarray:
    x, y, z = points.T
    in_depth = (z > 0) & (z < DEPTH)
    base = (x > 0) & (x < WIDTH) & (y > 0) & (y < WALL)
    walls = ((x > 0) & (x < WALL) | (x > WIDTH - WALL) & (x < WIDTH)) & (y > 0) & (y < HEIGHT)
    return in_depth & (base | walls)


def _in_any_hull(paths, points: np.ndarray) -> np.ndarray:
    inside = np.zeros(len(points), bool)
    for path in paths:
        equations = ConvexHull(trimesh.load(path).vertices).equations
        inside |= np.all(points @ equations[:, :3].T + equations[:, 3] <= 1e-6, axis=1)
    return inside


@pytest.fixture(scope="module")
def u_stl(tmp_path_factory):
    path = tmp_path_factory.mktemp("mesh") / "u.stl"
    _u_profile().export(path)
    return path


@pytest.fixture(scope="module")
def hulls(u_stl, tmp_path_factory):
    return collision_hulls(u_stl, tmp_path_factory.mktemp("cache") / "u")


@needs_coacd
def test_the_hulls_cover_the_solid_and_keep_the_slot_free(hulls):
    assert 2 <= len(hulls) <= CollisionParams().max_convex_hull
    assert [p.name for p in hulls] == [f"hull_{k}.stl" for k in range(len(hulls))]
    rng = np.random.default_rng(0)
    points = rng.uniform((0, 0, 0), (WIDTH, HEIGHT, DEPTH), size=(20000, 3))
    solid = points[_in_u(points)]
    assert _in_any_hull(hulls, solid).mean() > 0.99
    slot = np.array([(WIDTH / 2, (WALL + HEIGHT) / 2, DEPTH / 2), (WIDTH / 2, HEIGHT - 0.002, 0.002)])
    assert not _in_any_hull(hulls, slot).any()
    record = json.loads((hulls[0].parent / "collision.json").read_text())
    assert record["files"] == [p.name for p in hulls] and record["seconds"] > 0 and record["coacd_version"]
    assert record["settings"]["preprocess_mode"] == "off"  # a closed mesh is decomposed as it is


@needs_coacd
def test_a_second_call_takes_the_cached_hulls_and_new_settings_do_not(u_stl, hulls, monkeypatch):
    def no_coacd(*args, **kwargs):
        raise AssertionError("CoACD ran although the cache matched")

    monkeypatch.setattr(subprocess, "run", no_coacd)
    assert collision_hulls(u_stl, hulls[0].parent) == hulls
    with pytest.raises(AssertionError, match="CoACD ran"):
        collision_hulls(u_stl, hulls[0].parent, CollisionParams(max_convex_hull=2))
    assert not list(hulls[0].parent.parent.glob(".u.*")), "the scratch folder was left behind"


@needs_coacd
def test_a_changed_mesh_is_decomposed_again(u_stl, tmp_path):
    out = tmp_path / "u"
    first = collision_hulls(u_stl, out, CollisionParams(max_convex_hull=2))
    assert len(first) <= 2
    before = json.loads((out / "collision.json").read_text())["source_sha256"]
    bigger = tmp_path / "u.stl"
    _u_profile().apply_scale(2.0).export(bigger)
    second = collision_hulls(bigger, out, CollisionParams(max_convex_hull=2))
    assert json.loads((out / "collision.json").read_text())["source_sha256"] != before
    assert max(trimesh.load(p).bounds[1].max() for p in second) == pytest.approx(2 * WIDTH, rel=1e-3)


@pytest.mark.parametrize("content", [b"", b"solid part\n  facet normal 0 0 1\n  endfacet\nendsolid\n", b"\x00" * 90])
def test_an_empty_or_corrupt_stl_is_refused_naming_the_file(tmp_path, content):
    path = tmp_path / "broken.stl"
    path.write_bytes(content)
    with pytest.raises(CloudFileError, match="broken.stl"):
        collision_hulls(path, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_failed_decomposition_names_the_mesh_the_reason_and_the_fix(u_stl, tmp_path, monkeypatch):
    failed = subprocess.CompletedProcess([], 1, stdout="", stderr="warming up\nRuntimeError: no manifold\n")
    monkeypatch.setattr(subprocess, "run", lambda *args, **kwargs: failed)
    expected = r"u\.stl: .*failed: RuntimeError: no manifold \(repair the mesh"
    with pytest.raises(CollisionHullError, match=expected) as info:
        collision_hulls(u_stl, tmp_path / "u")
    assert isinstance(info.value, SimError) and info.value.path == str(u_stl)
    assert not (tmp_path / "u").exists() and not list(tmp_path.iterdir()), "a failed run left files behind"


def test_a_decomposition_that_takes_too_long_is_stopped(u_stl, tmp_path, monkeypatch):
    def too_slow(command, **kwargs):
        raise subprocess.TimeoutExpired(command, kwargs["timeout"])

    monkeypatch.setattr(subprocess, "run", too_slow)
    with pytest.raises(CollisionHullError, match=r"u\.stl: .*longer than 7 s.*CollisionParams\.timeout_s"):
        collision_hulls(u_stl, tmp_path / "u", CollisionParams(timeout_s=7))


def test_without_coacd_the_error_names_the_install(u_stl, tmp_path, monkeypatch):
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "coacd" else find_spec(name, *a))
    with pytest.raises(CollisionHullError, match="pip install coacd") as info:
        collision_hulls(u_stl, tmp_path / "u")
    assert "\n" not in str(info.value)


def test_the_threshold_scales_with_the_part_and_an_open_mesh_is_remeshed():
    closed, params = _u_profile(), CollisionParams()
    small, large = coacd_settings(closed), coacd_settings(closed.copy().apply_scale(3.0))
    assert small["threshold"] == pytest.approx(params.concavity / WIDTH, abs=1e-4)  # 5 mm of a 60 mm part
    assert large["threshold"] == params.min_threshold  # 5 mm of a 180 mm part would cost too much search
    assert small["preprocess_mode"] == large["preprocess_mode"] == "off"
    open_u = closed.copy()
    open_u.update_faces(np.arange(len(open_u.faces)) != 0)
    assert coacd_settings(open_u)["preprocess_mode"] == "on"


def test_a_stalled_search_is_retried_remeshed(u_stl, tmp_path, monkeypatch):
    commands = []

    def stall_then_finish(command, **kwargs):
        commands.append(command)
        if len(commands) == 1:
            return subprocess.CompletedProcess(command, STALLED, "", "did not settle within 20 rounds of cuts\n")
        trimesh.creation.box((0.01, 0.01, 0.01)).export(Path(command[4]) / "hull_0.stl")
        summary = {"files": ["hull_0.stl"], "seconds": 0.1, "rounds": 2, "coacd_version": "test"}
        return subprocess.CompletedProcess(command, 0, json.dumps(summary) + "\n", "")

    monkeypatch.setattr(subprocess, "run", stall_then_finish)
    hulls = collision_hulls(u_stl, tmp_path / "u")
    assert [json.loads(c[5])["preprocess_mode"] for c in commands] == ["off", "on"]
    record = json.loads((tmp_path / "u" / "collision.json").read_text())
    assert record["remeshed"] and record["settings"]["preprocess_mode"] == "off"  # the key: what was asked
    assert hulls == (tmp_path / "u" / "hull_0.stl",)


@needs_coacd
def test_a_search_that_never_settles_is_an_error_naming_the_fix(u_stl, tmp_path):
    with pytest.raises(CollisionHullError, match=r"u\.stl: .*within 1 rounds .*even remeshed.*max_rounds"):
        collision_hulls(u_stl, tmp_path / "u", CollisionParams(max_rounds=1))


def test_bad_settings_are_refused_naming_the_field():
    with pytest.raises(SimInputError, match="concavity must be in metres"):
        CollisionParams(concavity=5)
    with pytest.raises(SimInputError, match="max_convex_hull"):
        CollisionParams(max_convex_hull=0)
    with pytest.raises(SimInputError, match="timeout_s"):
        CollisionParams(timeout_s=0)


@needs_coacd
def test_a_simplified_copy_coacd_fails_on_is_given_up_for_the_mesh_as_it_is(u_stl, tmp_path, monkeypatch):
    import sim.parts.collision as collision

    real_worker = collision._run_worker
    searched = []

    def failing_on_the_copy(mesh_path, search_path, *args):
        searched.append(search_path.name)
        if search_path.name == "search.stl":
            raise CollisionHullError(mesh_path, "CoACD's convex decomposition failed: status -11", "repair it")
        return real_worker(mesh_path, search_path, *args)

    monkeypatch.setattr(collision, "simplified", lambda mesh, tolerance: mesh.copy())
    monkeypatch.setattr(collision, "_run_worker", failing_on_the_copy)
    hulls = collision_hulls(u_stl, tmp_path / "u")
    assert searched == ["search.stl", "u.stl"]
    record = json.loads((tmp_path / "u" / "collision.json").read_text())
    assert record["searched_faces"] == len(trimesh.load(u_stl).faces) and len(hulls) >= 2
