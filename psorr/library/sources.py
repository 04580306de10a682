"""What the CLI's MODELS argument names: a folder of meshes, mesh files, or one saved library (.npz)."""

from __future__ import annotations

import sys
from pathlib import Path

from psorr.errors import CloudFileError
from psorr.io.meshes import MESH_SUFFIXES
from psorr.library.cache import cache_dir
from psorr.library.models import ModelLibrary


def library_from_arguments(items, units: str | None = None, progress=None) -> ModelLibrary:
    """MODELS as the CLI takes it: a folder of meshes, mesh files, or one saved library (.npz)."""
    paths = [Path(i) for i in items]
    if len(paths) == 1 and paths[0].suffix.lower() == ".npz":
        if units is not None:
            raise CloudFileError(paths[0], f"--units {units} applies to meshes; a saved library is in metres already",
                                 "leave out --units")
        return ModelLibrary.load(paths[0])
    saved = next((p for p in paths if p.suffix.lower() == ".npz"), None)
    if saved is not None:
        raise CloudFileError(saved, "is a saved library, given with other MODELS",
                             "pass a saved library alone, or mesh files and folders without it")
    meshes = []
    for p in paths:
        if p.is_dir():
            found = sorted(f for f in p.iterdir() if f.suffix.lower() in MESH_SUFFIXES)
            if not found:
                raise CloudFileError(p, f"the folder holds no {'/'.join(MESH_SUFFIXES)} meshes", _mesh_folder_hint(p))
            skipped = sorted(f.name for f in p.iterdir() if f.is_file() and f not in found)
            if skipped:  # said, not silently passed over: a .glb or .iges there may be a part the user meant
                print(f"{p}: skipping {len(skipped)} file(s) that are not {'/'.join(MESH_SUFFIXES)} meshes: "
                      f"{', '.join(skipped[:8])}{' ...' if len(skipped) > 8 else ''}", file=sys.stderr)
            meshes += found
        else:
            meshes.append(p)
    print(f"training on {len(meshes)} mesh{'es' if len(meshes) != 1 else ''} (cached in {cache_dir()})",
          file=sys.stderr)
    return ModelLibrary.from_meshes(meshes, units=units, progress=progress)


def _mesh_folder_hint(folder: Path) -> str:
    """What to pass instead of a folder without meshes: its subfolders that hold some, if any."""
    nested = sorted(d for d in folder.iterdir()
                    if d.is_dir() and any(f.suffix.lower() in MESH_SUFFIXES for f in d.iterdir()))
    if nested:
        return "the meshes are one level down: pass " + " or ".join(str(d) for d in nested[:3])
    return "pass a folder of meshes, or the mesh files themselves"
