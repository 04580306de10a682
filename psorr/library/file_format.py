"""The .npz file of trained models (a saved library, or one cached model), and its checks.

One ``meta`` entry holds JSON: the format, the training settings (TrainParams, which the pair table is
rebuilt with on load) and per model its name, diameter, mesh hash, shape graph edges and primitives;
the arrays hold samples, meshes and primitive inliers. Everything read is checked, so that a torn,
edited or foreign file is refused with its name rather than failing later deep inside numpy.
"""

from __future__ import annotations

import json
import os
import uuid
import zipfile
from dataclasses import asdict, fields, is_dataclass

import numpy as np

from psorr.errors import CloudFileError, InvalidInputError
from psorr.types import OrientedBox, Primitive, PrimitiveKind, PrimitiveShapeGraph

FORMAT_VERSION = 3  # 3: models keep their mesh, for render-and-compare checks
_FIX = "pass mesh files, or a library written by ModelLibrary.save"


def save_models(path, models, params=None):
    """Write ``models`` (and the TrainParams ``params`` they were trained with, if given) to ``path``
    atomically: a crash never leaves a torn file. Returns ``path``."""
    arrays, meta = {}, {"format": FORMAT_VERSION, "models": []}
    if params is not None:
        meta["params"] = asdict(params)
    for i, m in enumerate(models):
        prims = m.graph.primitives
        arrays[f"m{i}_points"], arrays[f"m{i}_normals"] = m.points, m.normals
        arrays[f"m{i}_vertices"], arrays[f"m{i}_faces"] = m.vertices, m.faces
        for j, p in enumerate(prims):
            arrays[f"m{i}_p{j}_inliers"] = p.inliers
        meta["models"].append({
            "name": m.name, "diameter": m.diameter, "sha256": m.mesh_sha256, "edges": [list(e) for e in m.graph.edges],
            "primitives": [{"kind": p.kind.value, "params": list(p.params), "centroid": p.centroid.tolist(),
                            "box": [p.box.center.tolist(), p.box.rotation.tolist(), p.box.extent.tolist()]}
                           for p in prims]})
    # Settings may hold numpy numbers (np.int64(4) is a valid pair_points), which json does not know.
    arrays["meta"] = np.frombuffer(json.dumps(meta, default=_plain).encode(), dtype=np.uint8)
    path.parent.mkdir(parents=True, exist_ok=True)
    # A temporary name of this writer's own: two processes training one mesh at once (two test workers,
    # two users of one cache) each replace the file whole, where a shared name had one move the
    # other's half-written file, or find it gone.
    # (Not mkstemp: its files are private to the user, and a saved library should get the usual mode.)
    tmp = path.with_name(f"{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        with open(tmp, "xb") as f:
            np.savez_compressed(f, **arrays)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)  # absent when it could not even be created: the error to report is that one
        raise
    return path


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} cannot be saved in a library file")


def load_models(path, model_class, params_class):
    """The models in ``path`` (built with ``model_class``) and its training settings (a ``params_class``,
    or None when the file predates saving them). Raises CloudFileError naming the file for anything
    that is not such a file."""
    if not path.is_file():
        raise CloudFileError(path, "no such library file" if not path.exists() else "not a file", _FIX)
    if path.stat().st_size == 0:
        raise CloudFileError(path, "the file is empty (0 bytes)", _FIX)
    with open(path, "rb") as f:
        magic = f.read(4)
    if magic != b"PK\x03\x04":  # numpy's own message for other files invites unpickling them
        raise CloudFileError(path, "not a psorr model library (not an .npz archive)", _FIX)
    try:
        data = np.load(path, allow_pickle=False)
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError("an .npy array, not an .npz archive")
        with data:
            meta = json.loads(bytes(data["meta"]).decode())
            if not isinstance(meta, dict) or meta.get("format") != FORMAT_VERSION:
                found = meta.get("format") if isinstance(meta, dict) else None
                raise CloudFileError(path, f"library format {found}, this psorr reads {FORMAT_VERSION}",
                                     "retrain it from the meshes")
            params = _params(params_class, meta["params"]) if "params" in meta else None
            models = [_model(data, i, m, model_class) for i, m in enumerate(_listed(meta))]
    except CloudFileError:
        raise
    except (OSError, EOFError, ValueError, KeyError, TypeError, IndexError, AttributeError, zipfile.BadZipFile,
            json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise CloudFileError(path, f"not a psorr model library ({exc.__class__.__name__}: {exc})", _FIX) from None
    names = [m.name for m in models]
    if len(set(names)) != len(names):
        raise CloudFileError(path, f"holds models of the same name: {names}", "save each model once")
    return models, params


def _listed(meta: dict) -> list[dict]:
    models = meta["models"]
    if not isinstance(models, list) or not models or not all(isinstance(m, dict) for m in models):
        raise ValueError("it lists no models")
    return models


def _array(data, key: str, dtype, columns: int | None) -> np.ndarray:
    array = np.asarray(data[key])
    if array.dtype.kind not in ("fiu" if dtype is np.float64 else "iu"):
        raise ValueError(f"{key} holds {array.dtype}, not {np.dtype(dtype).name}")
    if (columns is None and array.ndim != 1) or (columns is not None and array.shape[1:] != (columns,)):
        raise ValueError(f"{key} has shape {array.shape}")
    if dtype is np.float64 and not np.isfinite(array).all():
        raise ValueError(f"{key} holds NaN or inf")
    return array.astype(dtype, copy=False)


def _model(data, i: int, m: dict, model_class):
    points, normals = _array(data, f"m{i}_points", np.float64, 3), _array(data, f"m{i}_normals", np.float64, 3)
    vertices, faces = _array(data, f"m{i}_vertices", np.float64, 3), _array(data, f"m{i}_faces", np.int64, 3)
    if len(points) < 3 or len(normals) != len(points):
        raise ValueError(f"model {i} has {len(points)} points and {len(normals)} normals")
    if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise ValueError(f"model {i}'s faces index beyond its {len(vertices)} vertices")
    prims = []
    for j, p in enumerate(m["primitives"]):
        inliers = _array(data, f"m{i}_p{j}_inliers", np.int64, None)
        if len(inliers) and (inliers.min() < 0 or inliers.max() >= len(points)):
            raise ValueError(f"model {i}, primitive {j}: inliers index beyond the {len(points)} points")
        box = OrientedBox(*(np.array(b, dtype=np.float64) for b in p["box"]))
        prims.append(Primitive(PrimitiveKind(p["kind"]), tuple(float(v) for v in p["params"]), inliers,
                               np.array(p["centroid"], dtype=np.float64), box))
    edges = tuple(tuple(int(k) for k in e) for e in m["edges"])
    try:
        graph = PrimitiveShapeGraph(tuple(prims), edges)
    except InvalidInputError as exc:
        raise ValueError(str(exc)) from None
    if not isinstance(m["name"], str) or not m["name"]:
        raise ValueError(f"model {i} has no name")
    return model_class(m["name"], points, normals, graph, float(m["diameter"]), str(m["sha256"]), vertices, faces)


def _params(cls, values: dict):
    """A params dataclass from its asdict() form: nested settings rebuilt, lists back to tuples. The class
    checks the values; a field it does not know means another psorr wrote the file."""
    defaults = cls()
    unknown = set(values) - {f.name for f in fields(cls)}
    if unknown:
        raise ValueError(f"training settings {sorted(unknown)} are unknown to this psorr")
    kwargs = {}
    for f in fields(cls):
        if f.name not in values:
            continue
        value, default = values[f.name], getattr(defaults, f.name)
        if is_dataclass(default):
            value = _params(type(default), value)
        elif isinstance(default, tuple):
            value = tuple(value)
        kwargs[f.name] = value
    try:
        return cls(**kwargs)
    except InvalidInputError as exc:
        raise ValueError(f"bad training settings: {exc}") from None
