"""The PCD (Point Cloud Library) codec.

PCD v0.7 stores a header (FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT,
POINTS, DATA) followed by the points as ascii rows, packed little-endian
records (``binary``) or LZF-compressed columns (``binary_compressed``). The
record decoders and the fields -> PointCloud mapping are shared with the PLY
codec, in :mod:`psorr.io.records`.

Everything here raises CloudFileError naming the file; it never lets a numpy or
lzf exception escape, because callers catch one error type per bad file.
"""

from __future__ import annotations

import struct

import lzf
import numpy as np

from psorr.errors import CloudFileError, InvalidInputError
from psorr.io.records import (
    NORMAL_NAMES,
    REEXPORT,
    Field,
    cloud_from_fields,
    decode_ascii,
    decode_binary,
    encode_records,
)
from psorr.types import PointCloud

# PCD (TYPE, SIZE) pairs -> numpy dtypes. PCD data is little-endian in practice (PCL
# writes host order and every host it runs on is little-endian).
_PCD_DTYPES = {
    ("F", 4): "<f4", ("F", 8): "<f8",
    ("I", 1): "i1", ("I", 2): "<i2", ("I", 4): "<i4", ("I", 8): "<i8",
    ("U", 1): "u1", ("U", 2): "<u2", ("U", 4): "<u4", ("U", 8): "<u8",
}  # fmt: skip
_PCD_KEYS = {"VERSION", "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT",
             "VIEWPOINT", "POINTS", "DATA"}  # fmt: skip
_PCD_DATA_KINDS = ("ascii", "binary", "binary_compressed")
_IDENTITY_POSE = np.array([0, 0, 0, 1, 0, 0, 0], dtype=float)
_MAX_HEADER_LINES = 64  # a real header has ~11 lines; stop early on binary junk
# ------------------------------------------------------------------------------ PCD


def _header_int(path, header: dict, key: str, default: int | None = None) -> int:
    values = header.get(key)
    if values is None and default is not None:
        return default
    try:
        (value,) = values
        value = int(value)
        if value < 0:
            raise ValueError
    except (TypeError, ValueError):
        raise CloudFileError(path, f"malformed PCD header: {key} must be one integer >= 0, got "
                             f"{' '.join(values or ['nothing'])}", REEXPORT) from None
    return value


def _parse_pcd_header(path, data: bytes) -> tuple[dict, int]:
    """Header lines up to and including DATA -> ({KEY: [values]}, offset of the data)."""
    header, position = {}, 0
    for _ in range(_MAX_HEADER_LINES):
        end = data.find(b"\n", position)
        end = len(data) if end < 0 else end
        try:
            line = data[position:end].decode("ascii").strip()
        except UnicodeDecodeError:
            break
        position = end + 1
        if line and not line.startswith("#"):
            key, *values = line.split()
            key = key.upper()
            if key not in _PCD_KEYS:
                raise CloudFileError(path, f"malformed PCD header: unknown line {line[:40]!r}",
                                     "is this really a PCD file? " + REEXPORT)
            header[key] = values
            if key == "DATA":
                return header, min(position, len(data))
        if end == len(data):
            break
    raise CloudFileError(path, "malformed PCD header: no DATA line", REEXPORT)


def _pcd_fields(path, header: dict) -> list[Field]:
    names = header.get("FIELDS", header.get("COLUMNS"))
    sizes, types = header.get("SIZE"), header.get("TYPE")
    if not names or sizes is None or types is None:
        raise CloudFileError(path, "malformed PCD header: FIELDS, SIZE and TYPE are required",
                             REEXPORT)
    counts = header.get("COUNT", ["1"] * len(names))
    if not len(names) == len(sizes) == len(types) == len(counts):
        raise CloudFileError(path, f"malformed PCD header: {len(names)} FIELDS but "
                             f"{len(sizes)} SIZE, {len(types)} TYPE, {len(counts)} COUNT",
                             REEXPORT)
    fields = []
    for name, size, kind, count in zip(names, sizes, types, counts, strict=True):
        try:
            dtype = np.dtype(_PCD_DTYPES[kind.upper(), int(size)])
            count = int(count)
            if count < 1:
                raise ValueError
        except (KeyError, ValueError):
            raise CloudFileError(path, f"malformed PCD header: field {name!r} has TYPE {kind} "
                                 f"SIZE {size} COUNT {count}", REEXPORT) from None
        fields.append(Field(name, dtype, count))
    real = [f.name for f in fields if f.name != "_"]
    if len(set(real)) != len(real):
        raise CloudFileError(path, f"malformed PCD header: repeated field in {names}", REEXPORT)
    return fields


def _check_viewpoint(path, header: dict) -> None:
    """Refuse a VIEWPOINT (tx ty tz qw qx qy qz) other than the identity.

    psorr takes points to be in the sensor frame: ignoring the pose would misplace every
    point without a word, and applying it would return coordinates that are not the
    file's, so the user converts the file once instead.
    """
    values = header.get("VIEWPOINT")
    if values is None:  # optional: PCL's default is the identity
        return
    try:
        pose = np.array([float(v) for v in values])
    except ValueError:
        pose = np.empty(0)
    if pose.shape != (7,):
        raise CloudFileError(path, f"malformed PCD header: VIEWPOINT must be 7 numbers, got "
                             f"{' '.join(values) or 'nothing'}", REEXPORT)
    # q and -q are the same rotation.
    if not (np.allclose(pose, _IDENTITY_POSE, rtol=0, atol=1e-6)
            or np.allclose(pose * [1, 1, 1, -1, -1, -1, -1], _IDENTITY_POSE, rtol=0, atol=1e-6)):
        raise CloudFileError(path, f"VIEWPOINT {' '.join(values)} is not the identity, so the "
                             "points are not in the sensor frame", "the points must be in the "
                             "sensor frame: transform them by the viewpoint's inverse and write "
                             "VIEWPOINT 0 0 0 1 0 0 0")


def decode_pcd(path, data: bytes) -> PointCloud:
    """The bytes of a PCD v0.7 file (ascii, binary or binary_compressed) -> a PointCloud.

    ``path`` only names the file in errors. x/y/z are metres (as stored); ``label``
    -> labels, ``rgb``/``rgba`` -> colors, ``normal_*`` -> normals. HEIGHT > 1 gives
    an organised cloud whose NaN pixels keep their rows. A VIEWPOINT other than the
    identity is refused. Other fields are ignored.
    """
    header, offset = _parse_pcd_header(path, data)
    fields = _pcd_fields(path, header)
    _check_viewpoint(path, header)
    width = _header_int(path, header, "WIDTH")
    height = _header_int(path, header, "HEIGHT", default=1)
    n = _header_int(path, header, "POINTS", default=width * height)
    if n != width * height:
        raise CloudFileError(path, f"malformed PCD header: POINTS {n} is not WIDTH x HEIGHT "
                             f"= {width} x {height}", REEXPORT)
    kind = (header["DATA"] or ["nothing"])[0].lower()
    if kind == "ascii":
        try:
            text = data[offset:].decode("ascii")
        except UnicodeDecodeError:
            raise CloudFileError(path, "DATA ascii holds non-text bytes", REEXPORT) from None
        columns = decode_ascii(path, text, fields, n)
    elif kind == "binary":
        columns = decode_binary(path, data, offset, fields, n, after=0)
    elif kind == "binary_compressed":
        columns = _decode_compressed(path, data, offset, fields, n)
    else:
        raise CloudFileError(path, f"malformed PCD header: DATA {kind!r} is not one of "
                             f"{', '.join(_PCD_DATA_KINDS)}", REEXPORT)
    columns.pop("_", None)  # padding
    organised = height > 1
    return cloud_from_fields(path, columns, width if organised else None,
                             height if organised else None)


def _decode_compressed(path, data: bytes, offset: int, fields: list[Field], n: int) -> dict:
    """binary_compressed: uint32 compressed size, uint32 raw size, then LZF data whose
    raw form stores the fields column by column (all x, then all y, ...)."""
    if len(data) - offset < 8:
        raise CloudFileError(path, "truncated data: the compressed-size words are missing",
                             REEXPORT)
    compressed_size, raw_size = struct.unpack_from("<II", data, offset)
    start = offset + 8
    if len(data) - start < compressed_size:
        raise CloudFileError(path, f"truncated data: {compressed_size} compressed bytes "
                             f"promised, {len(data) - start} present", REEXPORT)
    expected = n * sum(f.dtype.itemsize * f.count for f in fields)
    if raw_size != expected:
        raise CloudFileError(path, f"the data unpacks to {raw_size} bytes but {n} points of "
                             f"these fields need {expected}", REEXPORT)
    raw = b""
    if expected:
        try:
            raw = lzf.decompress(data[start:start + compressed_size], raw_size)
        except ValueError:
            raw = None
    if raw is None or len(raw) != expected:
        raise CloudFileError(path, "corrupt LZF data", REEXPORT)
    columns, position = {}, 0
    for f in fields:
        values = np.frombuffer(raw, dtype=f.dtype, count=n * f.count, offset=position)
        position += values.nbytes
        columns[f.name] = values if f.count == 1 else values.reshape(n, f.count)
    return columns


def _cloud_to_pcd_fields(cloud: PointCloud) -> tuple[list[Field], list[np.ndarray]]:
    """PCL's conventions: F4 coordinates/normals, rgba U4 (alpha 255), label U4 if it fits."""
    f4, u4 = np.dtype("<f4"), np.dtype("<u4")
    fields = [Field(axis, f4) for axis in "xyz"]
    columns = [cloud.points[:, i] for i in range(3)]
    if cloud.normals is not None:
        fields += [Field(name, f4) for name in NORMAL_NAMES[0]]
        columns += [cloud.normals[:, i] for i in range(3)]
    if cloud.colors is not None:
        if not np.isfinite(cloud.colors).all():
            raise InvalidInputError("colors hold NaN; PCD colours are packed 8-bit integers")
        rgb = np.rint(cloud.colors * 255).astype(np.uint32)
        fields.append(Field("rgba", u4))
        columns.append(0xFF000000 | rgb[:, 0] << 16 | rgb[:, 1] << 8 | rgb[:, 2])
    if cloud.labels is not None:
        labels = cloud.labels
        small = not len(labels) or (labels.min() >= 0 and labels.max() < 2**32)
        fields.append(Field("label", u4 if small else np.dtype("<i8")))
        columns.append(labels)
    return fields, columns


def encode_pcd(cloud: PointCloud, data: str = "binary") -> bytes:
    """``cloud`` -> a PCD v0.7 file with DATA ``ascii``, ``binary`` or ``binary_compressed``.

    Points and normals are stored as float32 (PCL's convention; ~1e-7 relative
    rounding), colours as 8-bit rgba, labels as uint32 (int64 if negative/huge).
    """
    if data not in _PCD_DATA_KINDS:
        raise InvalidInputError(f"data must be one of {', '.join(_PCD_DATA_KINDS)}, got {data!r}")
    fields, columns = _cloud_to_pcd_fields(cloud)
    if data == "binary_compressed":
        raw = b"".join(np.ascontiguousarray(c, dtype=f.dtype).tobytes()
                       for f, c in zip(fields, columns, strict=True))
        # LZF can grow incompressible data slightly; allow it rather than failing.
        packed = lzf.compress(raw, len(raw) + len(raw) // 16 + 64) if raw else b""
        body = struct.pack("<II", len(packed), len(raw)) + packed
    else:
        body = encode_records(fields, columns, ascii=data == "ascii")
    width, height = (cloud.width, cloud.height) if cloud.is_organised else (len(cloud), 1)
    kinds = {"f": "F", "i": "I", "u": "U"}
    header = "\n".join([
        "# .PCD v0.7 - Point Cloud Data file format",
        "VERSION 0.7",
        "FIELDS " + " ".join(f.name for f in fields),
        "SIZE " + " ".join(str(f.dtype.itemsize) for f in fields),
        "TYPE " + " ".join(kinds[f.dtype.kind] for f in fields),
        "COUNT " + " ".join("1" for _ in fields),
        f"WIDTH {width}",
        f"HEIGHT {height}",
        "VIEWPOINT 0 0 0 1 0 0 0",
        f"POINTS {len(cloud)}",
        f"DATA {data}",
    ]) + "\n"
    return header.encode("ascii") + body
