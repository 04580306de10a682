"""psorr.io.clouds's refusals: every malformed, empty, unknown or ambiguous cloud file gets an error that
names the file and what is wrong with it, and nothing is silently dropped or changed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from pcd_headers import pcd_header

from psorr.errors import CloudFileError
from psorr.io.clouds import CLOUD_SUFFIXES, read_cloud, write_cloud
from psorr.io.meshes import read_mesh
from psorr.types import PointCloud


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


@pytest.mark.parametrize("encoding", ["binary", "ascii"])
def test_ply_mesh_is_refused_as_a_cloud_but_reads_as_a_mesh(tmp_path, encoding):
    """Its 8 corners are no scan of the box: taking them as a cloud would mislead."""
    mesh = trimesh.creation.box()
    mesh.visual.vertex_colors = [255, 0, 0, 255]
    path = tmp_path / f"box_{encoding}.ply"
    path.write_bytes(mesh.export(file_type="ply", encoding=encoding))
    _expect_error(path, "mesh", "12 faces", "pass it as a model", "sample it to a cloud")
    assert len(read_mesh(path).faces) == 12


_XYZ_HEADER = ["x", "y", "z"], [4, 4, 4], "FFF"
_BAD_PCD = {
    "not_pcd": (b"hello world\n", "malformed PCD header"),
    "binary_junk": (bytes(range(256)) * 8, "malformed PCD header"),
    "no_data_line": (pcd_header(*_XYZ_HEADER, 2).rsplit(b"DATA", 1)[0], "no DATA"),
    "bad_type": (pcd_header(["x", "y", "z"], [4, 4, 4], "FQF", 1, data="ascii")
                 + b"1 2 3\n", "TYPE Q"),
    "size_count_mismatch": (pcd_header(["x", "y", "z"], [4, 4], "FFF", 1, data="ascii")
                            + b"1 2 3\n", "2 SIZE"),
    "points_not_w_x_h": (pcd_header(*_XYZ_HEADER, 2, data="ascii").replace(
        b"POINTS 2", b"POINTS 3") + b"1 2 3\n4 5 6\n", "POINTS 3"),
    "bad_width": (pcd_header(*_XYZ_HEADER, 2, data="ascii").replace(b"WIDTH 2", b"WIDTH two"),
                  "WIDTH"),
    "unknown_data": (pcd_header(*_XYZ_HEADER, 1, data="zip") + b"1 2 3\n", "DATA 'zip'"),
    "no_xyz": (pcd_header(["a", "b", "c"], [4, 4, 4], "FFF", 1, data="ascii") + b"1 2 3\n",
               "no x/y/z field"),
    "ascii_too_few_rows": (pcd_header(*_XYZ_HEADER, 3, data="ascii") + b"1 2 3\n4 5 6\n",
                           "3 points"),
    "ascii_too_many_rows": (pcd_header(*_XYZ_HEADER, 1, data="ascii") + b"1 2 3\n4 5 6\n",
                            "2 rows"),
    "ascii_ragged_row": (pcd_header(*_XYZ_HEADER, 2, data="ascii") + b"1 2 3\n4 5\n",
                         "columns"),
    "ascii_wrong_columns": (pcd_header(*_XYZ_HEADER, 1, data="ascii") + b"1 2 3 4\n",
                            "4 values"),
    "ascii_not_numbers": (pcd_header(*_XYZ_HEADER, 1, data="ascii") + b"1 two 3\n", "two"),
    "ascii_float_label": (pcd_header(["x", "y", "z", "label"], [4] * 4, "FFFU", 1,
                                      data="ascii") + b"1 2 3 0.5\n", "label"),
    "binary_truncated": (pcd_header(*_XYZ_HEADER, 3) + bytes(30), "truncated"),
    "compressed_no_sizes": (pcd_header(*_XYZ_HEADER, 3, data="binary_compressed") + b"\1\2",
                            "truncated"),
    "compressed_truncated": (pcd_header(*_XYZ_HEADER, 3, data="binary_compressed")
                             + np.array([100, 36], "<u4").tobytes() + b"abc", "truncated"),
    "compressed_wrong_size": (pcd_header(*_XYZ_HEADER, 3, data="binary_compressed")
                              + np.array([3, 30], "<u4").tobytes() + b"abc", "30 bytes"),
    "compressed_corrupt": (pcd_header(*_XYZ_HEADER, 3, data="binary_compressed")
                           + np.array([5, 36], "<u4").tobytes() + b"\xff" * 5, "corrupt"),
    "zero_points": (pcd_header(*_XYZ_HEADER, 0), "zero points"),
    "all_nan": (pcd_header(*_XYZ_HEADER, 2, data="ascii") + b"nan nan nan\n1 nan 2\n",
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
    "pcd_binary_extra_point": (".pcd", pcd_header(*_XYZ_HEADER, 1)
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
    "pcd_partial_normals": (".pcd", pcd_header(["x", "y", "z", "normal_x", "normal_y"], [4] * 5,
                                                "FFFFF", 1, data="ascii") + b"1 2 3 0 1\n",
                            ("incomplete normals", "no normal_z", "store all of")),
    "ply_partial_normals": (".ply", b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(b"{n}", b"1")
                            + b"property float nx\nproperty float nz\nend_header\n1 2 3 0 1\n",
                            ("incomplete normals", "no ny")),
    "pcd_viewpoint": (".pcd", pcd_header(*_XYZ_HEADER, 1, data="ascii").replace(
        b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 5 0 0 0 0 0 1") + b"1 2 3\n",
        ("VIEWPOINT 5 0 0 0 0 0 1", "sensor frame", "viewpoint's inverse",
         "write VIEWPOINT 0 0 0 1 0 0 0")),
    "pcd_viewpoint_malformed": (".pcd", pcd_header(*_XYZ_HEADER, 1, data="ascii").replace(
        b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 0 0 0 1") + b"1 2 3\n", ("7 numbers",)),
    "pcd_fractional_float_labels": (".pcd", pcd_header(["x", "y", "z", "label"], [4] * 4, "FFFF",
                                                        2) + np.array([[1, 2, 3, 0.5],
                                                                       [1, 2, 3, 1.7]], "<f4").tobytes(),
                                    ("2 non-integer", "0.5", "whole numbers that fit int64")),
    "ply_fractional_float_labels": (".ply", b"ply\nformat ascii 1.0\n" + _PLY_XYZ.replace(
        b"{n}", b"2") + b"property float label\nend_header\n1 2 3 0.5\n1 2 3 1.7\n",
        ("non-integer", "whole numbers")),
    "pcd_ascii_label_beyond_int64": (".pcd", pcd_header(*_PCD_XYZL, 1, data="ascii")
                                     + f"1 2 3 {2**64 - 1}\n".encode(),
                                     ("label", "2^53", "fit int64")),
    "pcd_binary_label_beyond_int64": (".pcd", pcd_header(*_PCD_XYZL, 1)
                                      + np.ones(3, "<f4").tobytes()
                                      + np.array([2**64 - 1], "<u8").tobytes(),
                                      ("18446744073709551615", "beyond int64", "fit int64")),
    "pcd_ascii_int_out_of_range": (".pcd", pcd_header(["x", "y", "z", "i"], [4, 4, 4, 1], "FFFU",
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
    header = pcd_header(["x", "y", "z", "label"], [4, 4, 4, 8], "FFFI", 2, data="ascii")
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
