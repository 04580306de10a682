"""What recognition derives from each model once, kept on disk beside the training cache.

A recognizer finds each model's near-symmetries (about 0.2 s a Prusa part, rendering turned samples against its
mesh) and its stable resting poses (about 0.07 s, trimesh's topple graph); 20 models took 5.8 s before the first
scene, in every process: every ``psorr recognize`` paid it again. Each is a function of the model's arrays and of
psorr's code, so it is kept under the training cache's folder (``derived/``), keyed by the hash of those arrays,
:func:`psorr.library.cache.code_fingerprint` and Open3D's version, as plain arrays (``.npz``, read without
pickle). An entry that cannot be read is derived again; a folder that cannot be written costs one warning and the
next process's shortcut.
"""

from __future__ import annotations

import hashlib
import os
import warnings
from collections.abc import Callable, Mapping, Sequence
from functools import cache
from importlib import metadata
from typing import TypeVar

import numpy as np

from psorr.library.cache import cache_dir, code_fingerprint

T = TypeVar("T")
_WARNED: set[str] = set()


def derived(kind: str, inputs: Sequence, derive: Callable[[], T], encode: Callable[[T], Mapping[str, np.ndarray]],
            decode: Callable[[Mapping[str, np.ndarray]], T]) -> T:
    """``derive()``, or what an earlier process kept of it: ``kind`` names what is derived, ``inputs`` (arrays and
    numbers) are everything it depends on but psorr's code; ``encode`` turns the value into named arrays and
    ``decode`` those arrays back into a value equal to it."""
    path = cache_dir() / "derived" / f"{kind}-{_key(kind, inputs)}.npz"
    kept = _read(path, decode)
    if kept is not None:
        return kept
    value = derive()
    _write(path, encode(value))
    return value


@cache
def _open3d_version() -> str:
    """Open3D's version: it measures the turned samples' distances, and training's fingerprint leaves it out."""
    try:
        return metadata.version("open3d")
    except metadata.PackageNotFoundError:
        return "absent"


def _key(kind: str, inputs: Sequence) -> str:
    digest = hashlib.sha256(f"{kind}|{code_fingerprint()}|open3d={_open3d_version()}".encode())
    for item in inputs:
        array = np.ascontiguousarray(item)
        digest.update(f"|{array.dtype.str}{array.shape}|".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()[:32]


def _read(path, decode):
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as stored:
            return decode({name: stored[name] for name in stored.files})
    except Exception:  # noqa: BLE001  a torn or foreign entry is derived again, not fatal
        return None


def _write(path, arrays: Mapping[str, np.ndarray]) -> None:
    part = path.with_name(f"{path.stem}.{os.getpid()}.part.npz")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(part, **arrays)
        os.replace(part, path)  # whole or not at all, though processes derive the same model at once
    except OSError as exc:
        if str(path.parent) not in _WARNED:
            _WARNED.add(str(path.parent))
            warnings.warn(f"cannot write the derived-model cache {path.parent} ({exc.strerror or exc}): each process "
                          "will derive its models' symmetries and resting poses again; set PSORR_CACHE to a "
                          "writable folder", stacklevel=3)
