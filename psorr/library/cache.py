"""The training cache: one trained model per file, under the user's cache directory.

An entry is keyed by everything a trained model depends on: the mesh bytes, the units, the training
settings, the file format, and the code that trains. That code is psorr's own sources and the
versions of the libraries that sample and decompose the mesh, so that a model trained by an older
psorr (a changed decomposition, say) is trained again, never silently reused. Training the 8
catalog parts takes about a second, which is all a change of code costs.

A cache that cannot be read is trained past, and one that cannot be written is warned about once;
neither stops training.
"""

from __future__ import annotations

import hashlib
import os
import warnings
from functools import cache
from importlib import metadata
from pathlib import Path

from psorr.library.file_format import FORMAT_VERSION, load_models, save_models

# Libraries whose results enter a trained model: surface sampling (trimesh), the random draws and
# fits (numpy, scipy), the graph cut (PyMaxflow).
_DEPENDENCIES = ("numpy", "scipy", "trimesh", "PyMaxflow")


def cache_dir() -> Path:
    """$PSORR_CACHE, else $XDG_CACHE_HOME/psorr, else ~/.cache/psorr."""
    if os.environ.get("PSORR_CACHE"):
        return Path(os.environ["PSORR_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "psorr"


@cache
def code_fingerprint() -> str:
    """A hash of psorr's sources and the versions of the libraries training uses (hex, computed once)."""
    digest = hashlib.sha256()
    package = Path(__file__).resolve().parents[1]  # psorr/, this file being psorr/library/cache.py
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes())
    for name in _DEPENDENCIES:
        try:
            version = metadata.version(name)
        except metadata.PackageNotFoundError:
            version = "absent"
        digest.update(f"{name}={version}\0".encode())
    return digest.hexdigest()


def entry_path(stem: str, mesh_sha256: str, units: str | None, params_fingerprint: str) -> Path:
    """Where the model trained from a mesh (its file stem and content hash) with these settings is kept."""
    key = f"{mesh_sha256}|{units}|{params_fingerprint}|{FORMAT_VERSION}|{code_fingerprint()}"
    return cache_dir() / f"{stem}-{hashlib.sha256(key.encode()).hexdigest()[:24]}.npz"


def load_entry(path: Path, model_class, params_class):
    """The cached model at ``path``, or None when there is none or it cannot be read (it is then retrained)."""
    if not path.is_file():
        return None
    try:
        return load_models(path, model_class, params_class)[0][0]
    except Exception:  # noqa: BLE001  a torn or foreign entry is retrained, not fatal
        return None


def store_entry(path: Path, model) -> bool:
    """Keep ``model`` at ``path``; False, after one warning that names the folder and the fix, if it cannot be
    written (a read-only home, PSORR_CACHE under a file): training stands, only the next run's shortcut is lost."""
    try:
        save_models(path, [model])
        return True
    except OSError as exc:
        warnings.warn(f"cannot write the training cache {path.parent} ({exc.strerror or exc}): these models will be "
                      "trained again next time; set PSORR_CACHE to a writable folder, or pass use_cache=False",
                      stacklevel=3)
        return False
