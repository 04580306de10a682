"""Which parts a world holds: each workpiece of a :class:`~sim.world.config.WorldConfig` as the cell builds it
(:func:`cell_parts`), and the bodies its instances become (:func:`instance_names`)."""

from __future__ import annotations

import hashlib
import json

import numpy as np

from psorr.synthetic.catalog import load_catalog
from sim.errors import SimInputError, WorldBuildError
from sim.parts import tell
from sim.parts.catalog_grasps import with_synthesised_grasps
from sim.parts.derive import CellPart, catalog_part, derive_part
from sim.parts.source import MeshPart
from sim.world.assets import COLLISION_DIR
from sim.world.config import WorldConfig

_REBUILD = "build them with: .venv/bin/python assets/workpieces/build_collision.py"


def collision_index() -> dict:
    """The CoACD index: part name -> {"files": [...], ...}; WorldBuildError if it was never built."""
    path = COLLISION_DIR / "index.json"
    if not path.is_file():
        raise WorldBuildError(f"{path} is missing: the workpieces' collision parts are not built; {_REBUILD}")
    return json.loads(path.read_text())["parts"]


def cell_parts(cfg: WorldConfig, progress=tell) -> dict[str, CellPart]:
    """Each workpiece of ``cfg`` as the cell builds it: a catalog part with its shipped hulls and grasps
    synthesised from its mesh (or the hand-written ones, as ``cfg.catalog_grasps`` says), a mesh part derived
    from its mesh (``progress`` hears of a slow first derivation; see :mod:`sim.parts`).

    Raises:
        SimInputError: a workpiece is neither a catalog part nor one of ``cfg.mesh_parts``.
        WorldBuildError: a catalog part's collision hulls are missing or stale.
        PartMeshError: a mesh cannot become a part.
    """
    catalog, meshes = load_catalog(), {p.name: p for p in cfg.mesh_parts}
    unknown = [n for n in cfg.workpieces if n not in catalog and n not in meshes]
    if unknown:
        raise SimInputError(f"unknown workpieces {unknown}; choose from {sorted(catalog)}, or give a mesh part")
    index = collision_index() if any(n not in meshes for n in cfg.workpieces) else {}
    parts = {}
    for name in cfg.workpieces:
        if name in meshes:
            parts[name] = derive_part(meshes[name], progress)
            continue
        if cfg.resting == "any":  # the catalog's grasps are for the upright part: derive grasps for every rest
            parts[name] = derive_part(_as_mesh_part(catalog[name]), progress)
            continue
        digest = hashlib.sha256(catalog[name].mesh_path.read_bytes()).hexdigest()
        if index.get(name, {}).get("source_sha256") != digest:
            raise WorldBuildError(f"the collision parts of {name} are missing or older than its mesh; {_REBUILD}")
        parts[name] = catalog_part(name, catalog, index)
        if cfg.catalog_grasps == "synthesised":
            parts[name] = with_synthesised_grasps(parts[name], progress)
    return parts


def instance_names(cfg: WorldConfig) -> dict[str, str]:
    """Body name -> part name, in task order: a part placed once is its own body; one placed n times (a mesh
    part's ``count``) becomes the bodies ``<name>_1`` .. ``<name>_<n>``."""
    counts = {p.name: p.count for p in cfg.mesh_parts}
    bodies = {}
    for name in cfg.workpieces:
        count = counts.get(name, 1)
        bodies.update({name: name} if count == 1 else {f"{name}_{k}": name for k in range(1, count + 1)})
    return bodies


def instance_colours(cfg: WorldConfig) -> dict[str, tuple[float, float, float]]:
    """Body name -> its own RGB, for the instances of a mesh part given one colour each (``color: [red,
    blue]``); the bodies of other parts are absent and take their part's colour."""
    bodies = {}
    for part in cfg.mesh_parts:
        if part.instance_colors is not None and len(set(part.instance_colors)) > 1:
            names = [b for b, t in instance_names(cfg).items() if t == part.name]
            bodies.update(zip(names, part.instance_colors))
    return bodies


def places(cfg: WorldConfig) -> dict[str, str]:
    """Body name -> where it is placed: ``"fixture"`` or ``"tote"`` (a mesh part's ``place``, else a fixture
    for a part resting upright and the tote for one resting any way)."""
    given = {p.name: p.place for p in cfg.mesh_parts}
    default = "tote" if cfg.resting == "any" else "fixture"
    return {body: given.get(part) or default for body, part in instance_names(cfg).items()}


def drawn_rests(cfg: WorldConfig, types: dict[str, str], meshes: dict, rng) -> dict:
    """Body -> (4, 4) T_table_model of the stable rest it is dropped in, drawn by probability from ``rng`` for
    every body when ``cfg.resting`` is ``"any"``; empty (every part upright, nothing drawn) otherwise."""
    if cfg.resting != "any":
        return {}
    from psorr.synthetic.resting import draw_rest, stable_rests

    return {body: draw_rest(rng, stable_rests(meshes[part])).T_table_model for body, part in types.items()}


def standing_height(cfg: WorldConfig, info) -> float:
    """The tallest (m) a part of ``info`` stands above the table: its upright height, or with ``cfg.resting``
    ``"any"`` the tallest of its stable rests (a plate drawn on its edge stands as high as it is wide)."""
    if cfg.resting != "any":
        return float(info.bounds()[1, 2])
    from psorr.synthetic.resting import stable_rests

    return max(rest.height for rest in stable_rests(info.load_mesh()))


def footprint_sides(mesh, T_table_model=None) -> np.ndarray:
    """(2,) the long and short side (m) of the smallest rectangle around ``mesh``'s footprint as it rests."""
    import trimesh

    T = np.eye(4) if T_table_model is None else T_table_model
    xy = mesh.convex_hull.vertices @ T[:2, :3].T + T[:2, 3]
    return np.sort(trimesh.bounds.oriented_bounds_2D(xy)[1])[::-1]


def footprint_bounds(mesh, T_table_model=None) -> np.ndarray:
    """(2, 2) lo and hi x, y of ``mesh`` (model frame) as it rests: upright, or turned by ``T_table_model``."""
    if T_table_model is None:
        return mesh.bounds[:, :2]
    xy = mesh.vertices @ T_table_model[:2, :3].T + T_table_model[:2, 3]
    return np.array([xy.min(axis=0), xy.max(axis=0)])


def _as_mesh_part(info) -> MeshPart:
    """A catalog part as a mesh part: its mesh (metres), name, colour and density."""
    from psorr.io.meshes import read_mesh

    volume = float(read_mesh(info.mesh_path).volume)
    return MeshPart(info.mesh_path, "m", info.name, color=tuple(info.color), density=info.mass / volume)
