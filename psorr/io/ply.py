"""The PLY codec: the vertex element of a PLY file <-> PointCloud.

Reads ascii, binary_little_endian and binary_big_endian files: vertex x/y/z, optional
nx/ny/nz, red/green/blue and label properties; elements before the vertices are skipped.
A mesh (a face element holding faces) is refused: read it with psorr.io.clouds.read_mesh.
Writes float64 points and normals, 8-bit colours and int32 labels. The record decoders
and the fields -> PointCloud mapping are shared with the PCD codec, in :mod:`psorr.io.records`.

Everything here raises CloudFileError naming the file (InvalidInputError for a cloud that
cannot be written), because callers catch one error type per bad file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from psorr.errors import CloudFileError, InvalidInputError
from psorr.io.records import Field, cloud_from_fields, decode_ascii, decode_binary, encode_records
from psorr.types import PointCloud

_PLY_TYPES = {
    "char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4", "uint": "u4",
    "float": "f4", "double": "f8", "int8": "i1", "uint8": "u1", "int16": "i2",
    "uint16": "u2", "int32": "i4", "uint32": "u4", "float32": "f4", "float64": "f8",
}  # fmt: skip
_PLY_ENDIAN = {"ascii": "<", "binary_little_endian": "<", "binary_big_endian": ">"}
_PLY_MAX_HEADER = 1 << 16  # bytes; a header longer than this is not a PLY header
_NORMALS = ("nx", "ny", "nz")
_FACE_ELEMENTS = ("face", "tristrips")  # the elements that make a PLY a surface
_BAD_PLY = "re-export the file, or check it was copied completely"


def _parse_ply_header(path: Path, data: bytes):
    """-> (format, elements [(name, count, [(property, dtype code or None for a list)])],
    offset of the data)."""
    end = data.find(b"end_header", 0, _PLY_MAX_HEADER)
    newline = data.find(b"\n", end)
    if not data.startswith(b"ply") or end < 0 or newline < 0:
        raise CloudFileError(path, "malformed PLY header: no 'ply' magic or 'end_header' line",
                             _BAD_PLY)
    try:
        lines = data[:end].decode("ascii").splitlines()[1:]
    except UnicodeDecodeError:
        raise CloudFileError(path, "malformed PLY header: non-text bytes", _BAD_PLY) from None
    fmt, elements = None, []
    for line in lines:
        words = line.split()
        try:
            if not words or words[0] in ("comment", "obj_info"):
                continue
            if words[0] == "format" and words[1] in _PLY_ENDIAN:
                fmt = words[1]
            elif words[0] == "element" and int(words[2]) >= 0:
                elements.append((words[1], int(words[2]), []))
            elif words[0] == "property" and words[1] == "list":
                elements[-1][2].append((words[4], None))  # variable length: no one dtype
            elif words[0] == "property":
                elements[-1][2].append((words[2], _PLY_TYPES[words[1]]))
            else:
                raise ValueError
        except (IndexError, KeyError, ValueError):
            raise CloudFileError(path, f"malformed PLY header line {line.strip()[:60]!r}",
                                 _BAD_PLY) from None
    if fmt is None:
        raise CloudFileError(path, "malformed PLY header: no supported 'format' line", _BAD_PLY)
    return fmt, elements, newline + 1


def _row_bytes(properties) -> int:
    """Bytes of one binary row of scalar properties."""
    return sum(np.dtype(code).itemsize for _, code in properties)


def decode_ply(path: Path, data: bytes) -> PointCloud:
    """The bytes of a PLY file (ascii or binary, either endianness) -> a PointCloud of its
    vertex element. ``path`` only names the file in errors; a mesh (faces) is refused."""
    fmt, elements, offset = _parse_ply_header(path, data)
    faces = sum(count for name, count, _ in elements if name in _FACE_ELEMENTS)
    if faces:
        # Its vertices alone are not a scan of the surface: corners only, no density.
        raise CloudFileError(path, f"it is a mesh ({faces} faces), not a point cloud",
                             "pass it as a model, or sample it to a cloud")
    index = next((i for i, (name, _, _) in enumerate(elements) if name == "vertex"), None)
    if index is None:
        raise CloudFileError(path, "no vertex element", "export the cloud's vertices")
    endian, skip_rows = _PLY_ENDIAN[fmt], 0
    for name, count, properties in elements[:index]:
        if any(code is None for _, code in properties) and fmt != "ascii":
            # Skipping variable-length rows needs a per-row walk; no exporter we know of
            # puts them before the vertices, so refuse rather than guess.
            raise CloudFileError(path, f"the {name!r} element with list properties comes "
                                 "before the vertices", "re-export with vertices first")
        offset += count * _row_bytes(properties)
        skip_rows += count
    _, count, properties = elements[index]
    if any(code is None for _, code in properties):
        raise CloudFileError(path, "the vertex element has list properties",
                             "re-export with scalar vertex properties only")
    names = [p for p, _ in properties]
    repeated = sorted({p for p in names if names.count(p) > 1})
    if repeated:
        raise CloudFileError(path, f"malformed PLY header: repeated vertex property "
                             f"{' '.join(repeated)}", "give each property its own name; " + _BAD_PLY)
    fields = [Field(p, np.dtype(endian + code)) for p, code in properties]
    later = [(n, props) for _, n, props in elements[index + 1:] if n]
    if fmt == "ascii":
        try:
            text = data[offset:].decode("ascii")
        except UnicodeDecodeError:
            raise CloudFileError(path, "ascii PLY data holds non-text bytes", _BAD_PLY) from None
        columns = decode_ascii(path, text, fields, count, skip_rows=skip_rows, exact=not later)
        if later:
            _check_ascii_rows(path, text, skip_rows + count + sum(n for n, _ in later))
    else:
        # Rows after the vertices have a known size unless they hold lists.
        lists = any(code is None for _, props in later for _, code in props)
        after = None if lists else sum(n * _row_bytes(props) for n, props in later)
        columns = decode_binary(path, data, offset, fields, count, after=after)
    return cloud_from_fields(path, columns)


def _check_ascii_rows(path: Path, text: str, expected: int) -> None:
    """Refuse ascii data whose row count differs from the header's elements in total."""
    rows = sum(1 for line in text.splitlines() if line.split("#", 1)[0].strip())
    if rows != expected:
        raise CloudFileError(path, f"the header declares {expected} rows of elements but the "
                             f"data holds {rows}", _BAD_PLY)


def encode_ply(cloud: PointCloud, binary: bool) -> bytes:
    """``cloud`` -> a binary_little_endian (or ascii) PLY file of one vertex element."""
    f8 = np.dtype("<f8")
    fields = [Field(axis, f8) for axis in "xyz"]
    columns = [cloud.points[:, i] for i in range(3)]
    if cloud.normals is not None:
        fields += [Field(name, f8) for name in _NORMALS]
        columns += [cloud.normals[:, i] for i in range(3)]
    if cloud.colors is not None:
        if not np.isfinite(cloud.colors).all():
            raise InvalidInputError("colors hold NaN; PLY colours are 8-bit integers")
        fields += [Field(name, np.dtype("u1")) for name in ("red", "green", "blue")]
        columns += list(np.rint(cloud.colors * 255).astype(np.uint8).T)
    if cloud.labels is not None:
        if cloud.labels.min() < -(2**31) or cloud.labels.max() >= 2**31:
            raise InvalidInputError("PLY labels are int32; these labels do not fit")
        fields.append(Field("label", np.dtype("<i4")))
        columns.append(cloud.labels)
    names = {"f8": "double", "u1": "uchar", "i4": "int"}
    header = [
        "ply",
        "format binary_little_endian 1.0" if binary else "format ascii 1.0",
        "comment written by psorr",
        f"element vertex {len(cloud)}",
        *(f"property {names[f.dtype.str[1:]]} {f.name}" for f in fields),
        "end_header",
    ]
    body = encode_records(fields, columns, ascii=not binary)
    return ("\n".join(header) + "\n").encode("ascii") + body
