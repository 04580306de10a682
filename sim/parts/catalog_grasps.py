"""The catalog parts' grasps, synthesised from their meshes as any part's are (:mod:`sim.parts.grasp_synthesis`)
and tried in MuJoCo (:mod:`sim.parts.grasp_trial`).

A catalog mesh rests upright in its model frame, so its grasps are those from above the upright part. They are
synthesised once per mesh and settings and cached beside the derived parts (``cache_dir()/parts/``). The
hand-written grasps in ``assets/workpieces/catalog.json`` stay as a reference: ``WorldConfig(catalog_grasps=
"hand-written")`` builds the cell with them, and the episodes benchmark compares the two.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np

from sim.parts import tell
from sim.parts.cache_files import write_whole
from sim.parts.derive import CellPart, grasp_settings
from sim.parts.grasp import Grasp

__all__ = ["with_synthesised_grasps"]

_KIND = "catalog-upright:tried:2"  # what a record holds: a record of another kind is made again


def with_synthesised_grasps(part: CellPart, progress=tell) -> CellPart:
    """``part`` (a catalog part) with grasps synthesised from its mesh in place of its hand-written ones.

    Raises:
        PartMeshError: no grasp from above holds the part (the message names the mesh).
    """
    info = part.info
    settings = grasp_settings()
    mesh = hashlib.sha256(info.mesh_path.read_bytes())
    seed = int(mesh.hexdigest()[:8], 16)  # of the mesh alone: other settings draw the same samples
    digest = mesh.copy()
    digest.update(f"{_KIND}:{settings}".encode())
    from psorr.library.cache import cache_dir

    path = cache_dir() / "parts" / digest.hexdigest()[:24] / f"{info.name}-grasps.json"
    grasps = _read(path)
    if grasps is None:
        if progress is not None:
            progress(f"synthesising the grasps of {info.name} from {info.mesh_path} (once per mesh)")
        grasps, trials = _synthesised(part, np.random.default_rng(seed))
        write_whole(path, json.dumps({"grasp_params": settings, "grasps": [g.as_record() for g in grasps],
                                      "grasp_trials": [dataclasses.asdict(t) for t in trials]}))
    return dataclasses.replace(part, grasps=grasps)


def _synthesised(part: CellPart, rng: np.random.Generator) -> tuple[tuple[Grasp, ...], tuple]:
    """The part's grasps from above, synthesised and then tried in MuJoCo (those that fail dropped), and the
    trials."""
    from sim.errors import PartMeshError, SimInputError
    from sim.parts.grasp_synthesis import synthesise_grasps
    from sim.parts.grasp_trial import verified_grasps

    fix = "give the part hand-written grasps in its catalog, and build the cell with catalog_grasps='hand-written'"
    mesh = part.info.load_mesh()
    try:
        found = synthesise_grasps(mesh, rng)
    except SimInputError as exc:
        raise PartMeshError(part.info.mesh_path, str(exc), fix) from None
    verified = verified_grasps(mesh, part.collision_files, part.info.mass, found)
    if not verified.grasps:
        why = "; ".join(f"{t.grasp} {t.why}" for t in verified.trials)
        raise PartMeshError(part.info.mesh_path, f"no synthesised grasp held in MuJoCo ({why})", fix)
    return verified.grasps, verified.trials


def _read(path) -> tuple[Grasp, ...] | None:
    try:
        return tuple(Grasp.from_record(g) for g in json.loads(path.read_text())["grasps"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
