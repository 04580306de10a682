"""Tests for psorr.io.clouds (and the PCD codec in psorr.io.pcd): round trips, hand-built files
in the layouts PCL and Open3D write, and the real OSD file. Meshes: test_mesh_io.py; bad input: test_io_bad_input.py."""

from __future__ import annotations

import lzf
import numpy as np
import pytest
from paths import SHARED
from pcd_headers import pcd_header

from psorr.errors import CloudFileError, InvalidInputError
from psorr.io.clouds import read_cloud, write_cloud
from psorr.types import PointCloud

LEARN0 = SHARED / "osd/learn/learn0.pcd"
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


@pytest.mark.filterwarnings("ignore:.*has no image layout")  # said; tested below
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


def test_ply_vertices_followed_by_other_rows_still_read(tmp_path):
    """An empty face element, or an element of scalar rows after the vertices, is no mesh."""
    header = "ply\nformat {fmt} 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
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
@pytest.mark.filterwarnings("ignore:.*has no image layout")
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
    header = pcd_header(["label", "x", "y", "z", "rgba"], [4] * 5, "UFFFU", 3, 2,
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
    header = pcd_header(["x", "y", "z", "_", "rgb"], [4, 4, 4, 1, 4], "FFFUF", 2,
                         counts=[1, 1, 1, 4, 1])
    (tmp_path / "pad.pcd").write_bytes(header + data.tobytes())
    cloud = read_cloud(tmp_path / "pad.pcd")
    _assert_points(cloud.points, np.array([[1.0, 3, 5], [2, 4, 6]]))
    np.testing.assert_allclose(cloud.colors, [[1, 128 / 255, 0], [0, 0, 1]])


def test_pcd_ascii_rgb_as_integer_or_float_text(tmp_path):
    """PCL writes a packed rgb float as its uint32 value, Open3D as the float itself."""
    as_float = np.array([0x00FF8000], "<u4").view("<f4")[0]
    header = pcd_header(["x", "y", "z", "rgb", "label"], [4] * 5, "FFFFU", 2, data="ascii")
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


def test_writing_labels_to_a_format_without_them_warns(tmp_path):
    cloud = PointCloud(np.zeros((3, 3)), labels=[1, 2, 3])
    with pytest.warns(UserWarning, match="labels are not written"):
        write_cloud(tmp_path / "plain.xyz", cloud)


def test_writing_an_image_to_a_format_without_a_layout_says_so(tmp_path):
    cloud = PointCloud(_organised_cloud().points, width=4, height=3)
    for suffix in (".ply", ".xyz"):
        with pytest.warns(UserWarning, match=f"c{suffix}: {suffix} has no image layout; the cloud's 4x3 rows"):
            write_cloud(tmp_path / f"c{suffix}", cloud)
        assert not read_cloud(tmp_path / f"c{suffix}").is_organised
