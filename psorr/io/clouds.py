"""Reading and writing point clouds (PCD, PLY, XYZ/TXT, NPY); meshes (STL, OBJ, PLY) are read by psorr.io.meshes.

Every failure caused by the file -- missing, empty, unknown suffix, malformed,
truncated, zero points, all points NaN -- raises CloudFileError naming the file
and what to do, never a bare numpy/trimesh exception. NaN rows are kept: an
organised cloud's invalid pixels stay in place and the caller decides.

What each format keeps when written:

======  ======  =======  =======  ======  =========  ===================================
format  points  normals  colours  labels  organised  notes
======  ======  =======  =======  ======  =========  ===================================
.pcd    yes     yes      yes      yes     yes        float32 points, 8-bit colours
.ply    yes     yes      yes      yes     no         float64 points, 8-bit colours
.xyz    yes     yes      no       no      no         text, exact float64 (also .txt)
.npy    yes     yes      no       no      yes        (N, 3|6) or (H, W, 3|6) float64
======  ======  =======  =======  ======  =========  ===================================
What a format cannot keep is said when writing (a warning), never dropped without a word.
"""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np

from psorr.checks.arrays import UNIT_TOLERANCE, not_unit
from psorr.errors import CloudFileError, InvalidInputError
from psorr.io.pcd import decode_pcd, encode_pcd
from psorr.io.ply import decode_ply, encode_ply
from psorr.io.records import cloud_from_fields, load_table
from psorr.types import PointCloud

CLOUD_SUFFIXES = (".pcd", ".ply", ".xyz", ".txt", ".npy")

_NORMALS = ("nx", "ny", "nz")


def require_suffix(path: Path, allowed: tuple[str, ...], what: str) -> str:
    suffix = path.suffix.lower()
    if suffix not in allowed:
        raise CloudFileError(path, f"unknown {what} format {suffix or '(no suffix)'!r}",
                             f"use one of {', '.join(allowed)}")
    return suffix


def require_file(path: Path) -> None:
    """CloudFileError unless ``path`` is an existing, non-empty file."""
    if not path.exists():
        raise CloudFileError(path, "file not found", "check the path and the working directory")
    if path.is_dir():
        raise CloudFileError(path, "is a directory", "pass a file inside it")
    if path.stat().st_size == 0:
        raise CloudFileError(path, "the file is empty", "re-export the file or check the copy")


def _read_bytes(path: Path) -> bytes:
    require_file(path)
    try:
        return path.read_bytes()
    except OSError as exc:
        raise CloudFileError(path, f"cannot read: {exc.strerror}", "check permissions") from None


# ------------------------------------------------------------------------------ read


def read_cloud(path) -> PointCloud:
    """Read a cloud from .pcd, .ply, .xyz/.txt or .npy (suffix case-insensitive).

    Returns a PointCloud of N points, (N, 3) float64 metres as stored in the file,
    with normals / colours in [0, 1] / int64 labels where the format holds them.
    PCD with HEIGHT > 1 and (H, W, 3) NPY give organised clouds (row-major, N = H*W);
    NaN rows are kept.

    .xyz/.txt: whitespace-separated ``x y z`` or ``x y z nx ny nz`` rows, ``#`` comments.
    .npy: (N, 3), (N, 6) (xyz + normals), (H, W, 3) or (H, W, 6) numeric array.
    .ply: vertex x/y/z, optional nx/ny/nz, red/green/blue and label properties.
    In .xyz/.txt/.npy the 6-column form must hold unit normals (finite rows).

    Raises:
        CloudFileError: unknown suffix, missing/empty/malformed/truncated file,
            more data than the header declares, zero points, every point NaN,
            columns 4-6 that are not unit normals, partial normals, non-integer
            labels or labels beyond int64, a PCD VIEWPOINT other than the identity,
            or a PLY mesh (faces).
    """
    path = Path(path)
    suffix = require_suffix(path, CLOUD_SUFFIXES, "point-cloud")
    data = _read_bytes(path)
    if suffix == ".pcd":
        return decode_pcd(path, data)
    if suffix == ".ply":
        return decode_ply(path, data)
    if suffix == ".npy":
        return _decode_npy(path, data)
    return _decode_xyz(path, data)


def _columns_to_cloud(path: Path, columns: np.ndarray, width=None, height=None) -> PointCloud:
    """(N, 3) xyz or (N, 6) xyz + normals -> a checked PointCloud."""
    if columns.shape[1] == 6:
        _check_unit_normals(path, columns[:, 3:])
    names = ("x", "y", "z", *_NORMALS)[: columns.shape[1]]
    return cloud_from_fields(path, dict(zip(names, columns.T, strict=True)), width, height)


def _check_unit_normals(path: Path, normals: np.ndarray) -> None:
    """Refuse columns 4-6 unless every finite row is a unit vector.

    Unnamed columns carry no meaning of their own, and x y z r g b is as common as
    x y z nx ny nz; colours taken as normals would silently spoil recognition.
    """
    off, finite, median = not_unit(normals)
    if off:
        raise CloudFileError(
            path, f"columns 4-6 are not unit normals: {off} of {finite} rows have a "
            f"norm outside 1 +- {UNIT_TOLERANCE} (median norm {median:.3g})",
            "columns 4-6 must be unit normals nx ny nz; for colours, use .ply or .pcd with "
            "named fields, or keep only x y z")


def _decode_xyz(path: Path, data: bytes) -> PointCloud:
    try:
        table = load_table(io.StringIO(data.decode("utf-8")))
    except (UnicodeDecodeError, ValueError) as exc:
        raise CloudFileError(path, f"malformed text cloud: {exc}",
                             "write whitespace-separated numbers, one point per row") from None
    if table.size == 0:
        table = np.empty((0, 3))  # only comments: cloud_from_fields reports zero points
    if table.shape[1] not in (3, 6):
        raise CloudFileError(path, f"rows have {table.shape[1]} columns",
                             "use 3 columns (x y z) or 6 (x y z nx ny nz)")
    return _columns_to_cloud(path, table)


def _decode_npy(path: Path, data: bytes) -> PointCloud:
    if not data.startswith(b"\x93NUMPY"):
        raise CloudFileError(path, "not a .npy file (no NUMPY magic bytes)",
                             "save the array with numpy.save")
    try:
        array = np.load(io.BytesIO(data), allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise CloudFileError(path, f"not a readable .npy array: {exc}",
                             "save the array with numpy.save") from None
    if not isinstance(array, np.ndarray):  # an .npz archive renamed to .npy
        raise CloudFileError(path, "holds an .npz archive, not one array", "use numpy.save")
    if array.dtype.kind not in "fiu" or array.ndim not in (2, 3) or array.shape[-1] not in (3, 6):
        raise CloudFileError(path, f"array of shape {array.shape} and dtype {array.dtype}",
                             "save a float array of shape (N, 3), (N, 6), (H, W, 3) or (H, W, 6)")
    if array.ndim == 3:
        height, width = array.shape[:2]
        return _columns_to_cloud(path, array.reshape(-1, array.shape[-1]), width, height)
    return _columns_to_cloud(path, array)



# ----------------------------------------------------------------------------- write


def write_cloud(
    path, cloud: PointCloud, *, binary: bool = True, compressed: bool = False
) -> None:
    """Write ``cloud`` as .pcd, .ply, .xyz/.txt or .npy, chosen by suffix.

    ``binary`` selects binary or ascii PCD/PLY (XYZ is always text, NPY always
    binary); ``compressed`` selects PCD ``binary_compressed`` (LZF). See the module
    docstring for what each format keeps; read_cloud reads every file written here.

    Raises:
        InvalidInputError: not a PointCloud, no points, or options that do not apply.
        CloudFileError: unknown suffix or the file cannot be written.
    """
    path = Path(path)
    suffix = require_suffix(path, CLOUD_SUFFIXES, "point-cloud")
    if not isinstance(cloud, PointCloud):
        raise InvalidInputError(f"write_cloud needs a PointCloud, got {type(cloud).__name__}")
    if len(cloud) == 0:
        raise InvalidInputError("cannot write a cloud with zero points; no reader would accept it")
    if compressed and (suffix != ".pcd" or not binary):
        raise InvalidInputError("compressed=True applies to binary .pcd files only")
    lost = [name for name in ("colors", "labels") if getattr(cloud, name) is not None]
    if suffix in (".xyz", ".txt", ".npy") and lost:
        # Nothing is dropped without a word: these formats hold points and normals only.
        warnings.warn(f"{path.name}: {suffix} keeps points and normals only; the cloud's "
                      f"{' and '.join(lost)} are not written (use .pcd or .ply to keep them)", stacklevel=2)
    if suffix in (".ply", ".xyz", ".txt") and cloud.height is not None and cloud.height > 1:
        warnings.warn(f"{path.name}: {suffix} has no image layout; the cloud's {cloud.width}x{cloud.height} "
                      "rows are written as an unorganised list, NaN rows included (use .pcd or .npy to keep "
                      "the layout)", stacklevel=2)
    if suffix == ".pcd":
        data = encode_pcd(cloud, "binary_compressed" if compressed else
                          "binary" if binary else "ascii")
    elif suffix == ".ply":
        data = encode_ply(cloud, binary)
    elif suffix == ".npy":
        data = _encode_npy(cloud)
    else:
        data = _encode_xyz(cloud)
    try:
        path.write_bytes(data)
    except OSError as exc:
        raise CloudFileError(path, f"cannot write: {exc.strerror}",
                             "check the directory exists and is writable") from None


def _xyz_normals(cloud: PointCloud) -> np.ndarray:
    """(N, 3) points or (N, 6) points + normals, float64."""
    if cloud.normals is None:
        return np.asarray(cloud.points)
    return np.hstack([cloud.points, cloud.normals])


def _encode_xyz(cloud: PointCloud) -> bytes:
    buffer = io.StringIO()
    columns = "x y z nx ny nz" if cloud.normals is not None else "x y z"
    # 17 significant digits give back exactly the same float64.
    np.savetxt(buffer, _xyz_normals(cloud), fmt="%.17g", header=columns)
    return buffer.getvalue().encode("ascii")


def _encode_npy(cloud: PointCloud) -> bytes:
    array = _xyz_normals(cloud)
    if cloud.is_organised:
        array = array.reshape(cloud.height, cloud.width, -1)
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()
