"""Tests for psorr.io (and the PCD codec in psorr.pcd): round trips, hand-built files
in the layouts PCL and Open3D write, every bad-input case, and the real OSD file."""

from __future__ import annotations

import time
from pathlib import Path

import lzf
import numpy as np
import pytest
import trimesh

from psorr.errors import CloudFileError, InvalidInputError
from psorr.io import CLOUD_SUFFIXES, read_cloud, read_mesh, write_cloud
from psorr.types import PointCloud

LEARN0 = Path(__file__).resolve().parents[2] / "shared/osd/learn/learn0.pcd"
F32 = 1e-6  # float32 storage of metre-scale coordinates rounds at ~1e-7 m
COLOUR_STEP = 0.5 / 255 + 1e-12  # 8-bit colour storage


def _organised_cloud(normals=True) -> PointCloud:
    """A 4 x 3 organised cloud with two NaN pixels, colours, labels and normals."""
    rng = np.random.default_rng(7)
    points = rng.uniform(-1.0, 2.0, size=(12, 3))
    points[[2, 9]] = np.nan
    unit = rng.normal(size=(12, 3))
    unit /= np.linalg.norm(unit, axis=1, keepdims=True)
    return PointCloud(
        points=points,
        normals=unit if normals else None,
        colors=rng.random((12, 3)),
        labels=rng.integers(0, 40, size=12),
        width=4,
        height=3,
    )


def _pcd_header(fields, sizes, types, width, height=1, data="binary", counts=None) -> bytes:
    counts = counts or [1] * len(fields)
    lines = [
        "# .PCD v0.7 - Point Cloud Data file format",
        "VERSION 0.7",
        "FIELDS " + " ".join(fields),
        "SIZE " + " ".join(map(str, sizes)),
        "TYPE " + " ".join(types),
        "COUNT " + " ".join(map(str, counts)),
        f"WIDTH {width}",
        f"HEIGHT {height}",
        "VIEWPOINT 0 0 0 1 0 0 0",
        f"POINTS {width * height}",
        f"DATA {data}",
    ]
    return ("\n".join(lines) + "\n").encode()


def _assert_points(actual, expected, atol=0.0):
    assert actual.shape == expected.shape
    assert np.array_equal(np.isnan(actual), np.isnan(expected)), "NaN rows moved or vanished"
    np.testing.assert_allclose(actual, expected, atol=atol, rtol=0)


# ------------------------------------------------------------------------ round trips


@pytest.mark.parametrize(
    "options", [{"binary": False}, {"binary": True}, {"compressed": True}],
    ids=["ascii", "binary", "binary_compressed"],
)
def test_pcd_round_trip_keeps_everything(tmp_path, options):
    cloud = _organised_cloud()
    path = tmp_path / "cloud.pcd"
    write_cloud(path, cloud, **options)
    back = read_cloud(path)
    assert (back.width, back.height) == (4, 3)
    _assert_points(back.points, cloud.points, atol=F32)
    np.testing.assert_allclose(back.normals, cloud.normals, atol=F32)
    np.testing.assert_allclose(back.colors, cloud.colors, atol=COLOUR_STEP)
    np.testing.assert_array_equal(back.labels, cloud.labels)
    assert back.labels.dtype == np.int64
    assert back.valid_mask.sum() == 10


def test_pcd_writes_pcl_conventions(tmp_path):
    path = tmp_path / "cloud.pcd"
    write_cloud(path, _organised_cloud(), binary=False)
    text = path.read_text()
    assert "FIELDS x y z normal_x normal_y normal_z rgba label\n" in text
    assert "TYPE F F F F F F U U\n" in text
    assert "WIDTH 4\nHEIGHT 3\n" in text
    assert "\nnan nan nan " in text  # the NaN pixel keeps its row


def test_pcd_negative_labels_survive(tmp_path):
    cloud = PointCloud(np.ones((3, 3)), labels=[-1, 0, 2**40])
    for options in ({"binary": False}, {"binary": True}, {"compressed": True}):
        write_cloud(tmp_path / "l.pcd", cloud, **options)
        np.testing.assert_array_equal(read_cloud(tmp_path / "l.pcd").labels, [-1, 0, 2**40])


def test_pcd_unorganised_stays_unorganised(tmp_path):
    cloud = PointCloud(np.arange(15.0).reshape(5, 3))
    write_cloud(tmp_path / "u.pcd", cloud)
    back = read_cloud(tmp_path / "u.pcd")
    assert not back.is_organised and back.normals is None and back.colors is None
    _assert_points(back.points, cloud.points)


@pytest.mark.parametrize("binary", [True, False], ids=["binary", "ascii"])
def test_ply_round_trip_with_colours_normals_labels(tmp_path, binary):
    cloud = _organised_cloud()
    path = tmp_path / "cloud.ply"
    write_cloud(path, cloud, binary=binary)
    back = read_cloud(path)
    _assert_points(back.points, cloud.points)  # PLY stores float64: exact
    np.testing.assert_array_equal(back.normals, cloud.normals)
    np.testing.assert_allclose(back.colors, cloud.colors, atol=COLOUR_STEP)
    np.testing.assert_array_equal(back.labels, cloud.labels)
    assert not back.is_organised  # PLY has no notion of an image grid


@pytest.mark.parametrize("encoding", ["binary", "ascii"])
def test_ply_mesh_is_refused_as_a_cloud_but_reads_as_a_mesh(tmp_path, encoding):
    """Its 8 corners are no scan of the box: taking them as a cloud would mislead."""
    mesh = trimesh.creation.box()
    mesh.visual.vertex_colors = [255, 0, 0, 255]
    path = tmp_path / f"box_{encoding}.ply"
    path.write_bytes(mesh.export(file_type="ply", encoding=encoding))
    _expect_error(path, "mesh", "12 faces", "pass it as a model", "sample it to a cloud")
    assert len(read_mesh(path).faces) == 12


def test_ply_vertices_followed_by_other_rows_still_read(tmp_path):
    """An empty face element, or an element of scalar rows after the vertices, is no mesh."""
    header = "ply\nformat {fmt} 1.0\n" + _PLY_XYZ.decode().format(n=2)
    ascii_text = (header.format(fmt="ascii") + "element face 0\nproperty list uchar int "
                  "vertex_indices\nelement edge 1\nproperty int a\nproperty int b\nend_header\n"
                  "1 2 3\n4 5 6\n0 1\n")
    (tmp_path / "a.ply").write_text(ascii_text)
    binary = (header.format(fmt="binary_little_endian") + "element edge 1\nproperty int a\n"
              "property int b\nend_header\n").encode()
    (tmp_path / "b.ply").write_bytes(binary + np.arange(1, 7, dtype="<f4").tobytes()
                                     + np.array([0, 1], "<i4").tobytes())
    for name in ("a.ply", "b.ply"):
        _assert_points(read_cloud(tmp_path / name).points, np.array([[1.0, 2, 3], [4, 5, 6]]))


def test_ply_big_endian(tmp_path):
    points = np.array([[1.5, -2.0, 3.25], [0.0, 1.0, np.nan]], dtype=">f4")
    header = (b"ply\nformat binary_big_endian 1.0\nelement vertex 2\n"
              b"property float x\nproperty float y\nproperty float z\nend_header\n")
    (tmp_path / "be.ply").write_bytes(header + points.tobytes())
    _assert_points(read_cloud(tmp_path / "be.ply").points, points.astype(float))


@pytest.mark.filterwarnings("ignore:.*keeps points and normals only")  # the loss is the point here
@pytest.mark.parametrize("suffix", [".xyz", ".txt", ".XYZ"])
@pytest.mark.parametrize("normals", [True, False])
def test_xyz_round_trip(tmp_path, suffix, normals):
    cloud = _organised_cloud(normals=normals)
    write_cloud(tmp_path / f"c{suffix}", cloud)
    back = read_cloud(tmp_path / f"c{suffix}")
    _assert_points(back.points, cloud.points)  # 17 significant digits: exact
    if normals:
        np.testing.assert_array_equal(back.normals, cloud.normals)
    else:
        assert back.normals is None


def test_xyz_reads_comments_and_blank_lines(tmp_path):
    (tmp_path / "c.xyz").write_text("# x y z\n1 2 3\n\n4 5 6  # trailing\nnan nan nan\n")
    _assert_points(read_cloud(tmp_path / "c.xyz").points,
                   np.array([[1, 2, 3], [4, 5, 6], [np.nan] * 3]))


@pytest.mark.filterwarnings("ignore:.*keeps points and normals only")  # the loss is the point here
def test_npy_round_trip_unorganised_and_organised(tmp_path):
    organised = _organised_cloud()
    write_cloud(tmp_path / "o.npy", organised)
    assert np.load(tmp_path / "o.npy").shape == (3, 4, 6)
    back = read_cloud(tmp_path / "o.npy")
    assert (back.width, back.height) == (4, 3)
    _assert_points(back.points, organised.points)
    np.testing.assert_array_equal(back.normals, organised.normals)

    flat = PointCloud(organised.points)
    write_cloud(tmp_path / "f.NPY", flat)
    assert np.load(tmp_path / "f.NPY").shape == (12, 3)
    back = read_cloud(tmp_path / "f.NPY")
    assert not back.is_organised
    _assert_points(back.points, flat.points)


def test_npy_shapes_accepted(tmp_path):
    grid = np.arange(2 * 5 * 3, dtype=np.float32).reshape(2, 5, 3)
    grid[1, 2] = np.nan
    np.save(tmp_path / "g.npy", grid)
    back = read_cloud(tmp_path / "g.npy")
    assert (back.width, back.height, len(back)) == (5, 2, 10)
    _assert_points(back.points, grid.reshape(-1, 3).astype(float))
    assert not back.valid_mask[7]  # row-major: pixel (row 1, col 2)

    xyzn = np.hstack([np.ones((4, 3)), np.tile([0.0, 0.0, 1.0], (4, 1))])
    np.save(tmp_path / "n.npy", xyzn)
    np.testing.assert_array_equal(read_cloud(tmp_path / "n.npy").normals, xyzn[:, 3:])
    np.save(tmp_path / "i.npy", np.arange(9).reshape(3, 3))  # integer millimetres, say
    assert read_cloud(tmp_path / "i.npy").points.dtype == np.float64


# ----------------------------------------------- hand-built files (PCL/Open3D layouts)


def test_pcd_binary_compressed_is_column_major(tmp_path):
    """Built by hand the way PCL does: label, x, y, z, rgba columns one after another."""
    labels = np.array([5, 5, 7, 0, 1, 2], dtype="<u4")
    xyz = np.array([[0.1, 0.2, 1.0], [0.3, 0.2, 1.1], [np.nan] * 3,
                    [0.5, 0.6, 1.2], [np.nan] * 3, [0.7, 0.8, 1.3]], dtype="<f4")
    rgba = np.array([0xFF102030, 0xFFFFFFFF, 0, 0x00FF0000, 0xFF0000FF, 0x8000FF00], "<u4")
    raw = labels.tobytes() + b"".join(xyz[:, i].tobytes() for i in range(3)) + rgba.tobytes()
    packed = lzf.compress(raw)
    body = np.array([len(packed), len(raw)], "<u4").tobytes() + packed
    header = _pcd_header(["label", "x", "y", "z", "rgba"], [4] * 5, "UFFFU", 3, 2,
                         "binary_compressed")
    (tmp_path / "pcl.pcd").write_bytes(header + body)
    cloud = read_cloud(tmp_path / "pcl.pcd")
    assert (cloud.width, cloud.height) == (3, 2)
    _assert_points(cloud.points, xyz.astype(float))
    np.testing.assert_array_equal(cloud.labels, labels)
    np.testing.assert_allclose(cloud.colors[0], np.array([0x10, 0x20, 0x30]) / 255)
    np.testing.assert_allclose(cloud.colors[1:], [[1, 1, 1], [0, 0, 0], [1, 0, 0], [0, 0, 1],
                                                  [0, 1, 0]])


def test_pcd_binary_with_padding_and_packed_float_rgb(tmp_path):
    """PCL's PointXYZRGB layout: x y z, 4 padding bytes, rgb as a float holding the bits."""
    record = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("_", "u1", 4),
                       ("rgb", "<u4")])
    data = np.zeros(2, record)
    data["x"], data["y"], data["z"] = [1, 2], [3, 4], [5, 6]
    data["rgb"] = [0x00FF8000, 0x000000FF]
    header = _pcd_header(["x", "y", "z", "_", "rgb"], [4, 4, 4, 1, 4], "FFFUF", 2,
                         counts=[1, 1, 1, 4, 1])
    (tmp_path / "pad.pcd").write_bytes(header + data.tobytes())
    cloud = read_cloud(tmp_path / "pad.pcd")
    _assert_points(cloud.points, np.array([[1.0, 3, 5], [2, 4, 6]]))
    np.testing.assert_allclose(cloud.colors, [[1, 128 / 255, 0], [0, 0, 1]])


def test_pcd_ascii_rgb_as_integer_or_float_text(tmp_path):
    """PCL writes a packed rgb float as its uint32 value, Open3D as the float itself."""
    as_float = np.array([0x00FF8000], "<u4").view("<f4")[0]
    header = _pcd_header(["x", "y", "z", "rgb", "label"], [4] * 5, "FFFFU", 2, data="ascii")
    body = f"1 2 3 {0xFF00FF00} 4\n4 5 6 {as_float:.10g} 9\n".encode()
    (tmp_path / "rgb.pcd").write_bytes(header + body)
    cloud = read_cloud(tmp_path / "rgb.pcd")
    np.testing.assert_allclose(cloud.colors, [[0, 1, 0], [1, 128 / 255, 0]])
    np.testing.assert_array_equal(cloud.labels, [4, 9])


def test_pcd_header_without_count_and_with_windows_newlines(tmp_path):
    text = ("VERSION .7\r\nFIELDS x y z\r\nSIZE 4 4 4\r\nTYPE F F F\r\nWIDTH 2\r\nHEIGHT 1\r\n"
            "POINTS 2\r\nDATA ascii\r\n1 2 3\r\n4 5 6\r\n")
    (tmp_path / "crlf.pcd").write_bytes(text.encode())
    _assert_points(read_cloud(tmp_path / "crlf.pcd").points, np.array([[1.0, 2, 3], [4, 5, 6]]))


def test_suffix_is_case_insensitive(tmp_path):
    cloud = _organised_cloud()
    write_cloud(tmp_path / "UPPER.PCD", cloud)
    assert len(read_cloud(tmp_path / "UPPER.PCD")) == 12


# ------------------------------------------------------------------------- bad input


def _expect_error(path, *fragments):
    with pytest.raises(CloudFileError) as caught:
        read_cloud(path)
    message = str(caught.value)
    assert Path(path).name in message
    for fragment in fragments:
        assert fragment in message, message
    return message


@pytest.mark.parametrize("suffix", CLOUD_SUFFIXES)
def test_missing_file(tmp_path, suffix):
    _expect_error(tmp_path / f"nowhere{suffix}", "not found")


@pytest.mark.parametrize("suffix", CLOUD_SUFFIXES)
def test_empty_file(tmp_path, suffix):
    (tmp_path / f"empty{suffix}").write_bytes(b"")
    _expect_error(tmp_path / f"empty{suffix}", "empty")


@pytest.mark.parametrize("name", ["scan.las", "scan", "scan.pcd.gz"])
def test_unknown_suffix_names_the_supported_ones(tmp_path, name):
    (tmp_path / name).write_bytes(b"1 2 3\n")
    _expect_error(tmp_path / name, "unknown", ".pcd", ".ply", ".xyz", ".npy")


def test_directory_is_not_a_cloud(tmp_path):
    (tmp_path / "dir.pcd").mkdir()
    _expect_error(tmp_path / "dir.pcd", "directory")


_XYZ_HEADER = ["x", "y", "z"], [4, 4, 4], "FFF"
_BAD_PCD = {
    "not_pcd": (b"hello world\n", "malformed PCD header"),
    "binary_junk": (bytes(range(256)) * 8, "malformed PCD header"),
    "no_data_line": (_pcd_header(*_XYZ_HEADER, 2).rsplit(b"DATA", 1)[0], "no DATA"),
    "bad_type": (_pcd_header(["x", "y", "z"], [4, 4, 4], "FQF", 1, data="ascii")
                 + b"1 2 3\n", "TYPE Q"),
    "size_count_mismatch": (_pcd_header(["x", "y", "z"], [4, 4], "FFF", 1, data="ascii")
                            + b"1 2 3\n", "2 SIZE"),
    "points_not_w_x_h": (_pcd_header(*_XYZ_HEADER, 2, data="ascii").replace(
        b"POINTS 2", b"POINTS 3") + b"1 2 3\n4 5 6\n", "POINTS 3"),
    "bad_width": (_pcd_header(*_XYZ_HEADER, 2, data="ascii").replace(b"WIDTH 2", b"WIDTH two"),
                  "WIDTH"),
    "unknown_data": (_pcd_header(*_XYZ_HEADER, 1, data="zip") + b"1 2 3\n", "DATA 'zip'"),
    "no_xyz": (_pcd_header(["a", "b", "c"], [4, 4, 4], "FFF", 1, data="ascii") + b"1 2 3\n",
               "no x/y/z field"),
    "ascii_too_few_rows": (_pcd_header(*_XYZ_HEADER, 3, data="ascii") + b"1 2 3\n4 5 6\n",
                           "3 points"),
    "ascii_too_many_rows": (_pcd_header(*_XYZ_HEADER, 1, data="ascii") + b"1 2 3\n4 5 6\n",
                            "2 rows"),
    "ascii_ragged_row": (_pcd_header(*_XYZ_HEADER, 2, data="ascii") + b"1 2 3\n4 5\n",
                         "columns"),
    "ascii_wrong_columns": (_pcd_header(*_XYZ_HEADER, 1, data="ascii") + b"1 2 3 4\n",
                            "4 values"),
    "ascii_not_numbers": (_pcd_header(*_XYZ_HEADER, 1, data="ascii") + b"1 two 3\n", "two"),
    "ascii_float_label": (_pcd_header(["x", "y", "z", "label"], [4] * 4, "FFFU", 1,
                                      data="ascii") + b"1 2 3 0.5\n", "label"),
    "binary_truncated": (_pcd_header(*_XYZ_HEADER, 3) + bytes(30), "truncated"),
    "compressed_no_sizes": (_pcd_header(*_XYZ_HEADER, 3, data="binary_compressed") + b"\1\2",
                            "truncated"),
    "compressed_truncated": (_pcd_header(*_XYZ_HEADER, 3, data="binary_compressed")
                             + np.array([100, 36], "<u4").tobytes() + b"abc", "truncated"),
    "compressed_wrong_size": (_pcd_header(*_XYZ_HEADER, 3, data="binary_compressed")
                              + np.array([3, 30], "<u4").tobytes() + b"abc", "30 bytes"),
    "compressed_corrupt": (_pcd_header(*_XYZ_HEADER, 3, data="binary_compressed")
                           + np.array([5, 36], "<u4").tobytes() + b"\xff" * 5, "corrupt"),
    "zero_points": (_pcd_header(*_XYZ_HEADER, 0), "zero points"),
    "all_nan": (_pcd_header(*_XYZ_HEADER, 2, data="ascii") + b"nan nan nan\n1 nan 2\n",
                "NaN"),
}


@pytest.mark.parametrize("case", _BAD_PCD, ids=list(_BAD_PCD))
def test_bad_pcd(tmp_path, case):
    content, fragment = _BAD_PCD[case]
    path = tmp_path / f"{case}.pcd"
    path.write_bytes(content)
    _expect_error(path, fragment)


_PLY_XYZ = b"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
_BAD_PLY = {
    "no_magic": (b"solid cube\n", "malformed PLY header"),
    "no_end_header": (b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"1"), "end_header"),
    "bad_format": (b"ply\nformat zipped 1.0\nend_header\n", "format zipped"),
    "bad_property": (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n"
                     b"1\n", "quad"),
    "no_vertices": (b"ply\nformat ascii 1.0\nelement face 0\n"
                    b"property list uchar int vertex_indices\nend_header\n", "no vertex"),
    "binary_truncated": (b"ply\nformat binary_little_endian 1.0\n"
                         + _PLY_XYZ.replace(b"{n}", b"5") + b"end_header\n" + bytes(20),
                         "truncated"),
    "ascii_too_few_rows": (b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"3")
                           + b"end_header\n1 2 3\n", "3 points"),
    "ascii_wrong_columns": (b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"1")
                            + b"end_header\n1 2\n", "2 values"),
    "zero_vertices": (b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"0")
                      + b"end_header\n", "zero points"),
    "all_nan": (b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"1")
                + b"end_header\nnan nan nan\n", "NaN"),
}


@pytest.mark.parametrize("case", _BAD_PLY, ids=list(_BAD_PLY))
def test_bad_ply(tmp_path, case):
    content, fragment = _BAD_PLY[case]
    path = tmp_path / f"{case}.ply"
    path.write_bytes(content)
    _expect_error(path, fragment)


@pytest.mark.parametrize(
    "text, fragment",
    [("1 2 3 4\n5 6 7 8\n", "4 columns"), ("1 2 3\n4 5\n", "columns"), ("1 2 x\n", "'x'"),
     ("# only a comment\n", "zero points"), ("nan nan nan\n", "NaN")],
    ids=["four_columns", "ragged", "not_numbers", "only_comments", "all_nan"],
)
def test_bad_xyz(tmp_path, text, fragment):
    (tmp_path / "bad.xyz").write_text(text)
    _expect_error(tmp_path / "bad.xyz", fragment)


# Each case: suffix, content, fragments the message must hold (the finding and the fix).
_PCD_XYZL = (["x", "y", "z", "label"], [4, 4, 4, 8], "FFFU")
_MESSY = {
    "xyz_colours_as_normals": (".xyz", b"1 2 3 200 180 40\n4 5 6 200 180 40\n",
                               ("not unit normals", "median norm 272", "must be unit normals",
                                ".ply or .pcd", "keep only x y z")),
    "xyz_one_row_not_unit": (".txt", b"1 2 3 0 0 1\n4 5 6 0 0 0.9\nnan nan nan nan nan nan\n",
                             ("1 of 2 rows", "must be unit normals")),
    "pcd_binary_extra_point": (".pcd", _pcd_header(*_XYZ_HEADER, 1)
                               + np.ones(6, "<f4").tobytes(),
                               ("declares 1 points", "12 more bytes", "point count match")),
    "ply_ascii_extra_rows": (".ply", b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"1")
                             + b"end_header\n1 2 3\n4 5 6\n7 8 9\n", ("1 points", "3 rows")),
    "ply_binary_extra_point": (".ply", b"ply\nformat binary_little_endian 1.0\n"
                               + _PLY_XYZ.replace(b"{n}", b"1") + b"end_header\n"
                               + np.ones(6, "<f4").tobytes(), ("declares 1 points", "12 more")),
    "ply_extra_rows_after_edges": (".ply", b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(
        b"{n}", b"1") + b"element edge 1\nproperty int a\nend_header\n1 2 3\n0\n0\n",
        ("declares 2 rows", "holds 3")),
    "ply_repeated_property": (".ply", b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"1")
                              + b"property float z\nend_header\n1 2 3 4\n",
                              ("repeated vertex property z", "its own name")),
    "pcd_partial_normals": (".pcd", _pcd_header(["x", "y", "z", "normal_x", "normal_y"], [4] * 5,
                                                "FFFFF", 1, data="ascii") + b"1 2 3 0 1\n",
                            ("incomplete normals", "no normal_z", "store all of")),
    "ply_partial_normals": (".ply", b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"1")
                            + b"property float nx\nproperty float nz\nend_header\n1 2 3 0 1\n",
                            ("incomplete normals", "no ny")),
    "pcd_viewpoint": (".pcd", _pcd_header(*_XYZ_HEADER, 1, data="ascii").replace(
        b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 5 0 0 0 0 0 1") + b"1 2 3\n",
        ("VIEWPOINT 5 0 0 0 0 0 1", "sensor frame", "viewpoint's inverse",
         "write VIEWPOINT 0 0 0 1 0 0 0")),
    "pcd_viewpoint_malformed": (".pcd", _pcd_header(*_XYZ_HEADER, 1, data="ascii").replace(
        b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 0 0 0 1") + b"1 2 3\n", ("7 numbers",)),
    "pcd_fractional_float_labels": (".pcd", _pcd_header(["x", "y", "z", "label"], [4] * 4, "FFFF",
                                                        2) + np.array([[1, 2, 3, 0.5],
                                                                       [1, 2, 3, 1.7]], "<f4").tobytes(),
                                    ("2 non-integer", "0.5", "whole numbers that fit int64")),
    "ply_fractional_float_labels": (".ply", b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(
        b"{n}", b"2") + b"property float label\nend_header\n1 2 3 0.5\n1 2 3 1.7\n",
        ("non-integer", "whole numbers")),
    "pcd_ascii_label_beyond_int64": (".pcd", _pcd_header(*_PCD_XYZL, 1, data="ascii")
                                     + f"1 2 3 {2**64 - 1}\n".encode(),
                                     ("label", "2^53", "fit int64")),
    "pcd_binary_label_beyond_int64": (".pcd", _pcd_header(*_PCD_XYZL, 1)
                                      + np.ones(3, "<f4").tobytes()
                                      + np.array([2**64 - 1], "<u8").tobytes(),
                                      ("18446744073709551615", "beyond int64", "fit int64")),
    "pcd_ascii_int_out_of_range": (".pcd", _pcd_header(["x", "y", "z", "i"], [4, 4, 4, 1], "FFFU",
                                                       1, data="ascii") + b"1 2 3 300\n",
                                   ("'i'", "uint8 range")),
}


@pytest.mark.filterwarnings("error")  # never a numpy RuntimeWarning on the way
@pytest.mark.parametrize("case", _MESSY, ids=list(_MESSY))
def test_refused_instead_of_silently_changed(tmp_path, case):
    suffix, content, fragments = _MESSY[case]
    path = tmp_path / f"{case}{suffix}"
    path.write_bytes(content)
    _expect_error(path, *fragments)


def test_npy_columns_4_to_6_must_be_unit_normals(tmp_path):
    np.save(tmp_path / "rgb.npy", np.hstack([np.ones((3, 3)), np.full((3, 3), 0.5)]))
    _expect_error(tmp_path / "rgb.npy", "not unit normals", "median norm 0.866")


def test_pcd_identity_viewpoints_and_in_range_labels_still_read(tmp_path):
    """q and -q are the same rotation; -1 is the "no label" value and must survive."""
    header = _pcd_header(["x", "y", "z", "label"], [4, 4, 4, 8], "FFFI", 2, data="ascii")
    for viewpoint in (b"VIEWPOINT 0 0 0 -1 0 0 0", b"VIEWPOINT 0 0 0 1 0 0 0"):
        (tmp_path / "v.pcd").write_bytes(header.replace(b"VIEWPOINT 0 0 0 1 0 0 0", viewpoint)
                                         + b"1 2 3 -1\n4 5 6 9007199254740992\n")
        np.testing.assert_array_equal(read_cloud(tmp_path / "v.pcd").labels, [-1, 2**53])


def test_bad_npy(tmp_path):
    (tmp_path / "text.npy").write_text("1 2 3\n")
    _expect_error(tmp_path / "text.npy", "not a .npy")
    cases = {"shape": np.zeros((3, 4)), "vector": np.zeros(3), "strings": np.array([["a"] * 3]),
             "zero": np.zeros((0, 3)), "nan": np.full((2, 2, 3), np.nan)}
    fragments = {"shape": "(3, 4)", "vector": "(3,)", "strings": "dtype", "zero": "zero points",
                 "nan": "NaN"}
    for name, array in cases.items():
        np.save(tmp_path / f"{name}.npy", array)
        _expect_error(tmp_path / f"{name}.npy", fragments[name])
    np.save(tmp_path / "cut.npy", np.ones((100, 3)))
    (tmp_path / "cut.npy").write_bytes((tmp_path / "cut.npy").read_bytes()[:-50])
    _expect_error(tmp_path / "cut.npy", "not a readable")


def test_nan_rows_are_kept_not_dropped(tmp_path):
    points = np.array([[np.nan] * 3, [1.0, 2, 3], [np.nan, 0, 0]])
    for suffix in CLOUD_SUFFIXES:
        write_cloud(tmp_path / f"n{suffix}", PointCloud(points))
        back = read_cloud(tmp_path / f"n{suffix}")
        assert len(back) == 3 and back.valid_mask.tolist() == [False, True, False], suffix


# ----------------------------------------------------------------------------- write


def test_write_errors(tmp_path):
    cloud = PointCloud(np.ones((2, 3)))
    with pytest.raises(CloudFileError, match="scan.las.*unknown"):
        write_cloud(tmp_path / "scan.las", cloud)
    with pytest.raises(CloudFileError, match="missing_dir"):
        write_cloud(tmp_path / "missing_dir" / "c.pcd", cloud)
    with pytest.raises(InvalidInputError, match="zero points"):
        write_cloud(tmp_path / "c.pcd", PointCloud(np.empty((0, 3))))
    with pytest.raises(InvalidInputError, match="compressed"):
        write_cloud(tmp_path / "c.ply", cloud, compressed=True)
    with pytest.raises(InvalidInputError, match="PointCloud"):
        write_cloud(tmp_path / "c.pcd", np.ones((2, 3)))
    assert not (tmp_path / "c.pcd").exists() and not (tmp_path / "c.ply").exists()


# ------------------------------------------------------------------------ real data


def test_reads_real_osd_learn0():
    if not LEARN0.is_file():
        pytest.skip(f"{LEARN0} is absent (the OSD data set is not installed)")
    cloud = read_cloud(LEARN0)
    assert (cloud.width, cloud.height, len(cloud)) == (640, 480, 640 * 480)
    assert cloud.labels is not None and cloud.colors is not None
    assert len(np.unique(cloud.labels)) > 1
    valid = cloud.valid_mask
    assert 0 < (~valid).sum() < len(cloud)  # some NaN pixels, kept in place
    finite = cloud.points[valid]
    # A Kinect-style table-top scene: metres, in front of the camera, within a few metres.
    assert np.all(finite[:, 2] > 0.2) and np.all(finite[:, 2] < 5.0)
    assert np.abs(finite[:, :2]).max() < 5.0
    best = min(_seconds(read_cloud, LEARN0) for _ in range(3))
    assert best < 0.1, f"reading learn0.pcd took {best * 1000:.0f} ms"


def _seconds(function, *args) -> float:
    start = time.perf_counter()
    function(*args)
    return time.perf_counter() - start


# ----------------------------------------------------------------------------- meshes


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".STL"])
def test_read_mesh(tmp_path, suffix):
    box = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    path = tmp_path / f"box{suffix}"
    box.export(path, file_type=suffix[1:].lower())
    mesh = read_mesh(path)
    assert isinstance(mesh, trimesh.Trimesh)
    assert len(mesh.faces) == 12
    np.testing.assert_allclose(mesh.extents, [0.1, 0.2, 0.3], atol=1e-6)


def test_read_mesh_joins_a_scene(tmp_path):
    scene = trimesh.Scene([trimesh.creation.box(),
                           trimesh.creation.box().apply_translation([3, 0, 0])])
    path = tmp_path / "two.obj"
    path.write_text(scene.export(file_type="obj"))
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


def test_writing_labels_to_a_format_without_them_warns(tmp_path):
    cloud = PointCloud(np.zeros((3, 3)), labels=[1, 2, 3])
    with pytest.warns(UserWarning, match="labels are not written"):
        write_cloud(tmp_path / "plain.xyz", cloud)
