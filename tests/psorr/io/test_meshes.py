"""Tests for psorr.io.meshes.read_mesh: the mesh formats, a scene of several meshes, and files that hold no
usable mesh. (Inside-out and mis-wound meshes: test_library.py.)"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from psorr.errors import CloudFileError
from psorr.io.meshes import read_mesh


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".STL"])
def test_read_mesh(tmp_path, suffix):
    box = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    path = tmp_path / f"box{suffix}"
    box.export(path, file_type=suffix[1:].lower())
    mesh = read_mesh(path)
    assert isinstance(mesh, trimesh.Trimesh)
    assert len(mesh.faces) == 12
    np.testing.assert_allclose(mesh.extents, [0.1, 0.2, 0.3], atol=1e-6)


@pytest.mark.parametrize("suffix", [".stl", ".ply"])
def test_read_mesh_merges_vertices_as_trimesh_does(tmp_path, suffix):
    # An STL repeats a vertex in each face that uses it; the merge must number them as trimesh.load does,
    # down to the file's face normals, for a model to train the same whichever reads it.
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.02).apply_translation([0.01, -0.005, 0.0])
    path = tmp_path / f"ball{suffix}"
    ball.export(path)
    expected, mesh = trimesh.load(path), read_mesh(path)
    assert len(mesh.vertices) == len(ball.vertices)
    assert np.array_equal(mesh.vertices, expected.vertices) and np.array_equal(mesh.faces, expected.faces)
    assert np.array_equal(mesh.face_normals, expected.face_normals)


def test_read_mesh_joins_a_scene(tmp_path):
    scene = trimesh.Scene([trimesh.creation.box(),
                           trimesh.creation.box().apply_translation([3, 0, 0])])
    path = tmp_path / "two.obj"
    path.write_text(scene.export(file_type="obj"))
    with pytest.warns(UserWarning, match="holds 2 meshes"):  # joined, and said: they may be separate parts
        assert len(read_mesh(path).faces) == 24


def _expect_mesh_error(path, *fragments):
    with pytest.raises(CloudFileError) as caught:
        read_mesh(path)
    for fragment in (Path(path).name, *fragments):
        assert fragment in str(caught.value)


def test_read_mesh_errors(tmp_path):
    _expect_mesh_error(tmp_path / "missing.stl", "not found")
    (tmp_path / "empty.obj").write_bytes(b"")
    _expect_mesh_error(tmp_path / "empty.obj", "empty")
    (tmp_path / "cloud.pcd").write_bytes(b"x")
    _expect_mesh_error(tmp_path / "cloud.pcd", ".stl", ".obj")
    # A PLY point cloud and an OBJ of bare vertices or lines hold no triangles.
    (tmp_path / "points.ply").write_bytes(trimesh.PointCloud(np.eye(3)).export(file_type="ply"))
    _expect_mesh_error(tmp_path / "points.ply", "no faces")
    (tmp_path / "lines.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n")
    _expect_mesh_error(tmp_path / "lines.obj", "lines.obj")
    (tmp_path / "junk.stl").write_bytes(b"\x00" * 90)
    _expect_mesh_error(tmp_path / "junk.stl", "junk.stl")
    # Triangles collapsed to a line would train a "model" with no surface.
    (tmp_path / "collapsed.obj").write_text("v 0 0 0\nv 0.1 0 0\nv 0.2 0 0\nf 1 2 3\n")
    _expect_mesh_error(tmp_path / "collapsed.obj", "collapsed.obj", "no area")
    # trimesh would drop the faces of a NaN vertex and train what is left.
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv nan 0 0.1\nf 1 2 3\nf 1 2 4\n")
    _expect_mesh_error(tmp_path / "nan.obj", "1 of its 4 vertices are NaN or infinite")


def test_an_open_mesh_is_taken_and_said(tmp_path):
    box = trimesh.creation.box(extents=(0.1, 0.06, 0.04))
    open_box = trimesh.Trimesh(box.vertices, box.faces[2:])  # one side's two triangles left out
    path = tmp_path / "open_box.stl"
    open_box.export(path)
    with pytest.warns(UserWarning, match=r"open_box.stl: the mesh is not closed \(4 edges border one face"):
        mesh = read_mesh(path)
    assert len(mesh.faces) == 10  # taken as it is, not repaired
