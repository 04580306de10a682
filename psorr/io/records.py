"""Typed point records, and named columns -> PointCloud: what the PCD and PLY codecs share.

PCD's binary records and PLY's vertex element are the same kind of thing: fixed-layout, typed
columns per point. The decoders here turn them (or ascii rows) into named columns, and
:func:`cloud_from_fields` maps those columns onto a checked :class:`~psorr.types.PointCloud`.
Everything raises CloudFileError naming the file, never a numpy exception.
"""

from __future__ import annotations

import io
import warnings
from dataclasses import dataclass

import numpy as np

from psorr.errors import CloudFileError, InvalidInputError
from psorr.types import PointCloud

_PACKED_COLOURS = ("rgba", "rgb")
NORMAL_NAMES = (("normal_x", "normal_y", "normal_z"), ("nx", "ny", "nz"))
_RGB_NAMES = ("red", "green", "blue")
_KNOWN_FIELDS = {"x", "y", "z", "label", *_PACKED_COLOURS, *_RGB_NAMES, *sum(NORMAL_NAMES, ())}
REEXPORT = "re-export the file, or check it was copied completely"
LABEL_FIX = "labels must be whole numbers that fit int64, -1 for no label"



@dataclass(frozen=True)
class Field:
    """One typed column of a record: ``count`` values of ``dtype`` per point."""

    name: str
    dtype: np.dtype
    count: int = 1


# --------------------------------------------------------------------------- records


def decode_binary(path, buffer, offset: int, fields: list[Field], n: int, *,
                  after: int | None = 0) -> dict:
    """Packed records (no padding) starting at ``offset`` -> {name: (n,) or (n, count)}.

    Exactly ``after`` bytes must follow the records (None: unknown, e.g. PLY list rows),
    so that points beyond the header's count are refused rather than dropped.
    """
    itemsize = sum(f.dtype.itemsize * f.count for f in fields)
    available = len(buffer) - offset
    if available < n * itemsize:
        raise CloudFileError(
            path, f"truncated data: {n} points need {n * itemsize} bytes, found {available}",
            REEXPORT)
    extra = None if after is None else available - n * itemsize - after
    if extra is not None and extra < 0:
        raise CloudFileError(path, f"truncated data: {-extra} bytes missing after the {n} "
                             "points", REEXPORT)
    if extra:
        raise CloudFileError(
            path, f"the header declares {n} points but {extra} more bytes of data follow them "
            f"({extra / itemsize:g} points' worth)",
            "make the header's point count match the data, or re-export the file")
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
    first ``n`` rows after ``skip_rows`` are read (PLY, where rows of further elements
    may follow; the caller checks those).
    """
    width = sum(f.count for f in fields)
    table = np.empty((0, width))
    if n:
        try:
            table = load_table(io.StringIO(text), skiprows=skip_rows,
                               max_rows=None if exact else n)
        except ValueError as exc:
            raise CloudFileError(path, f"malformed ascii data: {exc}", REEXPORT) from None
    if len(table) != n:
        raise CloudFileError(path, f"the header declares {n} points but the data holds "
                             f"{len(table)} rows", REEXPORT)
    if n and table.shape[1] != width:
        raise CloudFileError(path, f"rows have {table.shape[1]} values but the header declares "
                             f"{width} ({' '.join(f.name for f in fields)})", REEXPORT)
    out, start = {}, 0
    for f in fields:
        column = table[:, start] if f.count == 1 else table[:, start:start + f.count]
        start += f.count
        if f.name in _PACKED_COLOURS:
            out[f.name] = column  # keep float64 text values: see _unpack_colours
        elif f.dtype.kind == "f":
            out[f.name] = column.astype(f.dtype)  # round as binary data would be
        else:
            out[f.name] = _integer_column(path, f, column)
    return out


def _integer_column(path, field: Field, column: np.ndarray) -> np.ndarray:
    """Float64 text values -> ``field.dtype``, refusing any the cast would change."""
    if not (np.all(np.isfinite(column)) and np.all(column == np.rint(column))):
        raise CloudFileError(path, f"integer field {field.name!r} holds non-integer values",
                             REEXPORT)
    if field.name == "label" and len(column) and np.abs(column).max() > 2**53:
        # Text is parsed as float64, which rounds integers beyond 2**53 (2**64 - 1 -> 2**64).
        raise CloudFileError(path, f"the label field holds values as large as {np.abs(column).max():.3g}"
                             ", beyond the 2^53 that ascii data can carry exactly", LABEL_FIX)
    info = np.iinfo(field.dtype)
    # info.min and info.max + 1 are powers of two, so exact as float64.
    if len(column) and (column.min() < info.min or column.max() >= float(info.max + 1)):
        raise CloudFileError(path, f"integer field {field.name!r} holds values outside the "
                             f"{field.dtype.name} range {info.min}..{info.max}", REEXPORT)
    return column.astype(field.dtype)


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
        raise CloudFileError(path, f"cannot unpack colours stored as {packed.dtype}", REEXPORT)
    rgb = np.stack([(bits >> 16) & 0xFF, (bits >> 8) & 0xFF, bits & 0xFF], axis=1) / 255.0
    if packed.dtype == np.float64:
        rgb[np.isnan(packed)] = np.nan  # a NaN in text carries no colour; say so honestly
    return rgb


def cloud_from_fields(path, fields: dict, width: int | None = None,
                      height: int | None = None) -> PointCloud:
    """Named columns (x, y, z and optional normals, colours, label) -> a checked PointCloud.

    Recognises normal_x/normal_y/normal_z or nx/ny/nz, packed rgba/rgb or
    red/green/blue (integers are scaled by their maximum, floats taken as [0, 1]),
    and label. Raises CloudFileError for no points, all-NaN points, two of three normal
    fields, or labels that int64 would change; NaN rows are kept.
    """
    missing = [axis for axis in "xyz" if axis not in fields]
    if missing:
        raise CloudFileError(path, f"no {'/'.join(missing)} field (found: "
                             f"{' '.join(fields) or 'none'})", "store the coordinates as x y z")
    for name, column in fields.items():
        if column.ndim != 1 and name in _KNOWN_FIELDS:
            raise CloudFileError(path, f"field {name!r} has {column.shape[1]} values per point, "
                                 "expected 1", REEXPORT)
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
    for names in NORMAL_NAMES:
        present = [name for name in names if name in fields]
        if present and len(present) < 3:
            missing = " ".join(name for name in names if name not in fields)
            raise CloudFileError(path, f"incomplete normals: {' '.join(present)} but no {missing}",
                                 f"store all of {' '.join(names)}, or none of them")
        if present:
            normals = np.stack([fields[name] for name in names], axis=1).astype(np.float64)
    packed = next((fields[name] for name in _PACKED_COLOURS if name in fields), None)
    if packed is not None:
        colors = _unpack_colours(path, packed)
    elif all(name in fields for name in _RGB_NAMES):
        channels = [fields[name] for name in _RGB_NAMES]
        scale = np.iinfo(channels[0].dtype).max if channels[0].dtype.kind in "iu" else 1.0
        colors = np.stack(channels, axis=1).astype(np.float64) / scale
    if "label" in fields:
        labels = fields["label"]  # PointCloud refuses values that int64 would change
    try:
        return PointCloud(points, normals, colors, labels, width, height)
    except InvalidInputError as exc:
        raise CloudFileError(path, str(exc), REEXPORT) from None
