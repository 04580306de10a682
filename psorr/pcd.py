"""The PCD (Point Cloud Library) codec, plus the typed-record helpers the PLY codec shares.

PCD v0.7 stores a header (FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT,
POINTS, DATA) followed by the points as ascii rows, packed little-endian
records (``binary``) or LZF-compressed columns (``binary_compressed``). PLY's
vertex element is the same kind of typed record, so the record decoders and
the fields -> PointCloud mapping live here and psorr.io reuses them.

Everything here raises CloudFileError naming the file; it never lets a numpy or
lzf exception escape, because callers catch one error type per bad file.
"""

from __future__ import annotations

import io
import struct
import warnings
from dataclasses import dataclass

import lzf
import numpy as np

from psorr.errors import CloudFileError, InvalidInputError
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
_MAX_HEADER_LINES = 64  # a real header has ~11 lines; stop early on binary junk
_PACKED_COLOURS = ("rgba", "rgb")
_NORMAL_NAMES = (("normal_x", "normal_y", "normal_z"), ("nx", "ny", "nz"))
_RGB_NAMES = ("red", "green", "blue")
_KNOWN_FIELDS = {"x", "y", "z", "label", *_PACKED_COLOURS, *_RGB_NAMES, *sum(_NORMAL_NAMES, ())}
_REEXPORT = "re-export the file, or check it was copied completely"


@dataclass(frozen=True)
class Field:
    """One typed column of a record: ``count`` values of ``dtype`` per point."""

    name: str
    dtype: np.dtype
    count: int = 1


# --------------------------------------------------------------------------- records


def decode_binary(path, buffer, offset: int, fields: list[Field], n: int) -> dict:
    """Packed records (no padding) starting at ``offset`` -> {name: (n,) or (n, count)}."""
    itemsize = sum(f.dtype.itemsize * f.count for f in fields)
    available = len(buffer) - offset
    if available < n * itemsize:
        raise CloudFileError(
            path, f"truncated data: {n} points need {n * itemsize} bytes, found {available}",
            _REEXPORT)
    # Padding fields ("_" in PCD) may repeat, so give every column a unique key.
    keys = [f"f{i}" for i in range(len(fields))]
    offsets = np.cumsum([0] + [f.dtype.itemsize * f.count for f in fields[:-1]]).tolist()
    formats = [f.dtype if f.count == 1 else (f.dtype, (f.count,)) for f in fields]
    record = np.dtype({"names": keys, "formats": formats, "offsets": offsets,
                       "itemsize": itemsize})
    records = np.frombuffer(buffer, dtype=record, count=n, offset=offset)
    return {f.name: records[key] for f, key in zip(fields, keys, strict=True)}


def load_table(text: io.StringIO, **options) -> np.ndarray:
    """numpy.loadtxt of float64 rows with ``#`` comments, as (rows, columns); raises ValueError.

    loadtxt's C parser is fast and reports ragged rows. Text holding no rows gives an
    empty table without loadtxt's "input contained no data" warning: the callers
    report the emptiness as an error themselves.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        try:
            return np.loadtxt(text, dtype=np.float64, comments="#", ndmin=2, **options)
        except ValueError as exc:
            # Drop loadtxt's advice to pass `usecols`: it does not apply to a bad file.
            raise ValueError(str(exc).split("; use `usecols`")[0]) from None


def decode_ascii(path, text: str, fields: list[Field], n: int, *, skip_rows: int = 0,
                 exact: bool = True) -> dict:
    """Whitespace-separated rows (``#`` comments) -> {name: array}.

    With ``exact`` the text must hold exactly ``n`` rows (PCD); otherwise only the
    first ``n`` rows after ``skip_rows`` are read (PLY, where faces may follow).
    """
    width = sum(f.count for f in fields)
    table = np.empty((0, width))
    if n:
        try:
            table = load_table(io.StringIO(text), skiprows=skip_rows,
                               max_rows=None if exact else n)
        except ValueError as exc:
            raise CloudFileError(path, f"malformed ascii data: {exc}", _REEXPORT) from None
    if len(table) != n:
        raise CloudFileError(path, f"the header declares {n} points but the data holds "
                             f"{len(table)} rows", _REEXPORT)
    if n and table.shape[1] != width:
        raise CloudFileError(path, f"rows have {table.shape[1]} values but the header declares "
                             f"{width} ({' '.join(f.name for f in fields)})", _REEXPORT)
    out, start = {}, 0
    for f in fields:
        column = table[:, start] if f.count == 1 else table[:, start:start + f.count]
        start += f.count
        if f.name in _PACKED_COLOURS:
            out[f.name] = column  # keep float64 text values: see _unpack_colours
        elif f.dtype.kind == "f":
            out[f.name] = column.astype(f.dtype)  # round as binary data would be
        elif np.all(np.isfinite(column)) and np.all(column == np.rint(column)):
            out[f.name] = column.astype(f.dtype)
        else:
            raise CloudFileError(path, f"integer field {f.name!r} holds non-integer values",
                                 _REEXPORT)
    return out


def encode_records(fields: list[Field], columns: list[np.ndarray], *, ascii: bool) -> bytes:
    """Columns -> packed little-endian records, or ascii rows that round-trip exactly."""
    record = np.dtype([(f"f{i}", f.dtype) for i, f in enumerate(fields)])
    table = np.empty(len(columns[0]), dtype=record)
    for i, column in enumerate(columns):
        table[f"f{i}"] = column
    if not ascii:
        return table.tobytes()
    # 9 / 17 significant digits are the fewest that always give back the same float32 / 64.
    formats = {"f4": "%.9g", "f8": "%.17g"}
    buffer = io.StringIO()
    np.savetxt(buffer, table, fmt=[formats.get(f.dtype.str[1:], "%d") for f in fields])
    return buffer.getvalue().encode("ascii")


# ----------------------------------------------------------------- fields -> PointCloud


def _unpack_colours(path, packed: np.ndarray) -> np.ndarray:
    """Packed 0xAARRGGBB colours -> (N, 3) RGB in [0, 1]; alpha is not kept."""
    if packed.dtype == np.float32:  # binary "rgb" F 4: the float's bits are the colour
        bits = packed.view(np.uint32)
    elif packed.dtype.kind in "iu":
        bits = packed.astype(np.uint32)
    elif packed.dtype == np.float64:  # ascii text
        # PCL writes packed colours as integers, Open3D as the float with those bits.
        # Integers in uint32 range are taken as the bits, anything else as a float32.
        integral = np.isfinite(packed) & (packed == np.floor(packed))
        integral &= (packed >= 0) & (packed < 2**32)
        bits = np.where(integral, packed, 0).astype(np.uint32)
        bits[~integral] = packed[~integral].astype(np.float32).view(np.uint32)
    else:
        raise CloudFileError(path, f"cannot unpack colours stored as {packed.dtype}", _REEXPORT)
    rgb = np.stack([(bits >> 16) & 0xFF, (bits >> 8) & 0xFF, bits & 0xFF], axis=1) / 255.0
    if packed.dtype == np.float64:
        rgb[np.isnan(packed)] = np.nan  # a NaN in text carries no colour; say so honestly
    return rgb


def cloud_from_fields(path, fields: dict, width: int | None = None,
                      height: int | None = None) -> PointCloud:
    """Named columns (x, y, z and optional normals, colours, label) -> a checked PointCloud.

    Recognises normal_x/normal_y/normal_z or nx/ny/nz, packed rgba/rgb or
    red/green/blue (integers are scaled by their maximum, floats taken as [0, 1]),
    and label. Raises CloudFileError for no points or all-NaN points; NaN rows are kept.
    """
    missing = [axis for axis in "xyz" if axis not in fields]
    if missing:
        raise CloudFileError(path, f"no {'/'.join(missing)} field (found: "
                             f"{' '.join(fields) or 'none'})", "store the coordinates as x y z")
    for name, column in fields.items():
        if column.ndim != 1 and name in _KNOWN_FIELDS:
            raise CloudFileError(path, f"field {name!r} has {column.shape[1]} values per point, "
                                 "expected 1", _REEXPORT)
    n = len(fields["x"])
    if n == 0:
        raise CloudFileError(path, "the cloud has zero points",
                             "check it was exported from a non-empty cloud")
    points = np.empty((n, 3))
    for i, axis in enumerate("xyz"):
        points[:, i] = fields[axis]
    if not np.isfinite(points).all(axis=1).any():
        raise CloudFileError(path, f"all {n} points are NaN or infinite",
                             "check the capture; the sensor returned no valid depth")
    normals = colors = labels = None
    for names in _NORMAL_NAMES:
        if all(name in fields for name in names):
            normals = np.stack([fields[name] for name in names], axis=1).astype(np.float64)
    packed = next((fields[name] for name in _PACKED_COLOURS if name in fields), None)
    if packed is not None:
        colors = _unpack_colours(path, packed)
    elif all(name in fields for name in _RGB_NAMES):
        channels = [fields[name] for name in _RGB_NAMES]
        scale = np.iinfo(channels[0].dtype).max if channels[0].dtype.kind in "iu" else 1.0
        colors = np.stack(channels, axis=1).astype(np.float64) / scale
    if "label" in fields:
        labels = fields["label"]
        if labels.dtype.kind == "f":
            if not np.all(labels == np.rint(labels)):  # also false for NaN
                raise CloudFileError(path, "the label field holds non-integer values",
                                     _REEXPORT)
        labels = labels.astype(np.int64)
    try:
        return PointCloud(points, normals, colors, labels, width, height)
    except InvalidInputError as exc:
        raise CloudFileError(path, str(exc), _REEXPORT) from None


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
                             f"{' '.join(values or ['nothing'])}", _REEXPORT) from None
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
                                     "is this really a PCD file? " + _REEXPORT)
            header[key] = values
            if key == "DATA":
                return header, min(position, len(data))
        if end == len(data):
            break
    raise CloudFileError(path, "malformed PCD header: no DATA line", _REEXPORT)


def _pcd_fields(path, header: dict) -> list[Field]:
    names = header.get("FIELDS", header.get("COLUMNS"))
    sizes, types = header.get("SIZE"), header.get("TYPE")
    if not names or sizes is None or types is None:
        raise CloudFileError(path, "malformed PCD header: FIELDS, SIZE and TYPE are required",
                             _REEXPORT)
    counts = header.get("COUNT", ["1"] * len(names))
    if not len(names) == len(sizes) == len(types) == len(counts):
        raise CloudFileError(path, f"malformed PCD header: {len(names)} FIELDS but "
                             f"{len(sizes)} SIZE, {len(types)} TYPE, {len(counts)} COUNT",
                             _REEXPORT)
    fields = []
    for name, size, kind, count in zip(names, sizes, types, counts, strict=True):
        try:
            dtype = np.dtype(_PCD_DTYPES[kind.upper(), int(size)])
            count = int(count)
            if count < 1:
                raise ValueError
        except (KeyError, ValueError):
            raise CloudFileError(path, f"malformed PCD header: field {name!r} has TYPE {kind} "
                                 f"SIZE {size} COUNT {count}", _REEXPORT) from None
        fields.append(Field(name, dtype, count))
    real = [f.name for f in fields if f.name != "_"]
    if len(set(real)) != len(real):
        raise CloudFileError(path, f"malformed PCD header: repeated field in {names}", _REEXPORT)
    return fields


def decode_pcd(path, data: bytes) -> PointCloud:
    """The bytes of a PCD v0.7 file (ascii, binary or binary_compressed) -> a PointCloud.

    ``path`` only names the file in errors. x/y/z are metres (as stored); ``label``
    -> labels, ``rgb``/``rgba`` -> colors, ``normal_*`` -> normals. HEIGHT > 1 gives
    an organised cloud whose NaN pixels keep their rows. VIEWPOINT is not applied.
    Other fields are ignored.
    """
    header, offset = _parse_pcd_header(path, data)
    fields = _pcd_fields(path, header)
    width = _header_int(path, header, "WIDTH")
    height = _header_int(path, header, "HEIGHT", default=1)
    n = _header_int(path, header, "POINTS", default=width * height)
    if n != width * height:
        raise CloudFileError(path, f"malformed PCD header: POINTS {n} is not WIDTH x HEIGHT "
                             f"= {width} x {height}", _REEXPORT)
    kind = (header["DATA"] or ["nothing"])[0].lower()
    if kind == "ascii":
        try:
            text = data[offset:].decode("ascii")
        except UnicodeDecodeError:
            raise CloudFileError(path, "DATA ascii holds non-text bytes", _REEXPORT) from None
        columns = decode_ascii(path, text, fields, n)
    elif kind == "binary":
        columns = decode_binary(path, data, offset, fields, n)
    elif kind == "binary_compressed":
        columns = _decode_compressed(path, data, offset, fields, n)
    else:
        raise CloudFileError(path, f"malformed PCD header: DATA {kind!r} is not one of "
                             f"{', '.join(_PCD_DATA_KINDS)}", _REEXPORT)
    columns.pop("_", None)  # padding
    organised = height > 1
    return cloud_from_fields(path, columns, width if organised else None,
                             height if organised else None)


def _decode_compressed(path, data: bytes, offset: int, fields: list[Field], n: int) -> dict:
    """binary_compressed: uint32 compressed size, uint32 raw size, then LZF data whose
    raw form stores the fields column by column (all x, then all y, ...)."""
    if len(data) - offset < 8:
        raise CloudFileError(path, "truncated data: the compressed-size words are missing",
                             _REEXPORT)
    compressed_size, raw_size = struct.unpack_from("<II", data, offset)
    start = offset + 8
    if len(data) - start < compressed_size:
        raise CloudFileError(path, f"truncated data: {compressed_size} compressed bytes "
                             f"promised, {len(data) - start} present", _REEXPORT)
    expected = n * sum(f.dtype.itemsize * f.count for f in fields)
    if raw_size != expected:
        raise CloudFileError(path, f"the data unpacks to {raw_size} bytes but {n} points of "
                             f"these fields need {expected}", _REEXPORT)
    raw = b""
    if expected:
        try:
            raw = lzf.decompress(data[start:start + compressed_size], raw_size)
        except ValueError:
            raw = None
    if raw is None or len(raw) != expected:
        raise CloudFileError(path, "corrupt LZF data", _REEXPORT)
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
        fields += [Field(name, f4) for name in _NORMAL_NAMES[0]]
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
