"""Everything the cell needs of a part, from its mesh alone: :func:`derive_part`, cached by the mesh's hash.

A part is its mesh turned to rest upright (its most probable stable pose, the footprint's centre at the
origin, the table at z = 0: the model frame every catalog part has), its mass and inertia from a density,
its symmetries (found from the mesh), its stable rests, its collision hulls (CoACD, in a subprocess) and
its parallel-jaw grasps (synthesised). :func:`catalog_part` gives the same for a catalog part, whose
hulls and grasps ship with the assets.
"""

from __future__ import annotations

import hashlib
import json
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from psorr.errors import PsorrError
from psorr.geometry.solids import is_closed, open_edges
from psorr.synthetic.catalog import WorkpieceInfo
from sim.errors import PartMeshError
from sim.parts import tell
from sim.parts.cache_files import write_whole
from sim.parts.grasp import Grasp
from sim.parts.source import MeshPart

DERIVATION = 1
"""Bumped when what is derived changes, so older caches are derived again."""
GRASPED_SHARE = 0.99
MAX_GRASPED_RESTS = 8
"""Grasps are synthesised for the most probable rests that hold 99% of the chance that a dropped part lands
so, and at most 8 of them: the rare rest left (a part balanced on an edge) is reported as having no grasp."""


@dataclass(frozen=True, eq=False)
class CellPart:
    """One part type as the cell builds it.

    Attributes:
        info: its mesh (STL, metres, model frame), mass, colour and symmetries.
        collision_files: (K,) STL files whose convex hulls are its collision geoms (model frame, metres).
        grasps: its parallel-jaw grasps, best first.
        source: the mesh the task named, or None for a catalog part.
    """

    info: WorkpieceInfo
    collision_files: tuple[Path, ...]
    grasps: tuple[Grasp, ...]
    source: MeshPart | None = None

    @property
    def name(self) -> str:
        return self.info.name


def catalog_part(name: str, catalog: dict, collision: dict) -> CellPart:
    """The catalog part ``name`` with its shipped hulls (``collision``: the collision index) and grasps."""
    from sim.skills.grasps import load_grasps
    from sim.world.assets import COLLISION_DIR

    files = tuple(COLLISION_DIR / f for f in collision[name]["files"])
    return CellPart(catalog[name], files, load_grasps().get(name, ()))


def cache_folder(part: MeshPart) -> Path:
    """Where ``part``'s derived files live: the training cache's folder, ``parts/``, by the hash of the mesh
    file's bytes, its unit and :data:`DERIVATION`."""
    from psorr.library.cache import cache_dir

    digest = hashlib.sha256(part.path.read_bytes())
    digest.update(f"{part.units}:{DERIVATION}".encode())
    return cache_dir() / "parts" / digest.hexdigest()[:24]


def upright_mesh(part: MeshPart) -> trimesh.Trimesh:
    """The part's mesh in metres, resting upright in its model frame; PartMeshError when it cannot be a part."""
    from psorr.io.meshes import read_mesh
    from psorr.synthetic.resting import stable_rests

    with warnings.catch_warnings(record=True) as heard:  # an open mesh's warning: refused below instead
        warnings.simplefilter("always")
        try:
            mesh = read_mesh(part.path)
        except PsorrError as exc:
            raise PartMeshError(part.path, str(exc).removeprefix(f"{part.path}: "),
                                "re-export it as STL, OBJ or PLY") from None
    if not is_closed(mesh):  # a solid; bodies touching along an edge of four faces are one
        raise PartMeshError(part.path, f"is not closed ({open_edges(mesh)} edges border a hole or a sheet): the cell "
                            "needs its volume for the mass and a solid for collisions",
                            "close it (e.g. trimesh.repair.fill_holes, or MeshLab's Close Holes) and export again")
    for warning in heard:
        warnings.warn_explicit(warning.message, warning.category, warning.filename, warning.lineno)
    mesh.apply_scale(part.scale)
    rest = stable_rests(mesh)[0]
    mesh.apply_transform(rest.T_table_model)
    _check_size(part, rest.footprint)
    mesh.apply_transform(_squared_up(rest.footprint))
    return mesh


def _squared_up(outline: np.ndarray) -> np.ndarray:
    """(4, 4) turn about z and shift that lay the footprint's smallest rectangle along x (its long side) and y,
    centred on the origin: the generated fixture's pocket is that rectangle."""
    T_rect_table, extents = trimesh.bounds.oriented_bounds_2D(outline)
    T = np.eye(4)
    T[:2, :2], T[:2, 3] = T_rect_table[:2, :2], T_rect_table[:2, 2]
    if extents[1] > extents[0]:  # the long side along x
        T = trimesh.transformations.rotation_matrix(np.pi / 2, [0, 0, 1]) @ T
    return T


def _check_size(part: MeshPart, outline: np.ndarray) -> None:
    from psorr.hypotheses.outline import OutlineParams
    from psorr.synthetic.resting import polygon_area

    footprint = polygon_area(outline)
    least = OutlineParams().min_area
    if footprint < least:
        raise PartMeshError(part.path, f"is too small for the sensor: resting, it covers {footprint * 1e4:.2f} cm^2 "
                            f"of the table, and the recognizer sees parts of {least * 1e4:.0f} cm^2 and more "
                            f"(read in {part.units}: is that the file's unit?)",
                            "give the right units, or a larger part")


def derive_part(part: MeshPart, progress=tell) -> CellPart:
    """``part`` as the cell builds it, derived once and then read from the cache (see the module).

    Args:
        part: the mesh and what the task says of it.
        progress: called with a line of text before a slow derivation (None: silent).

    Raises:
        PartMeshError: the mesh cannot become a part (unreadable, not closed, too small for the sensor, too
            wide for the gripper from every side); the message names the file and the fix.
    """
    folder = cache_folder(part)
    record = folder / f"{part.name}.json"
    if record.is_file():
        cached = _read_record(record, part)
        if cached is not None:
            return cached
    if progress is not None:
        progress(f"deriving the part {part.name} from {part.path} (collision hulls and grasps; once per mesh)")
    start = time.perf_counter()
    mesh = upright_mesh(part)
    folder.mkdir(parents=True, exist_ok=True)
    mesh_path = folder / f"{part.name}.stl"
    write_whole(mesh_path, mesh.export(file_type="stl"))
    hulls = _hulls(part, mesh_path, folder)
    grasps, trials = _grasps(part, mesh, hulls, np.random.default_rng(int(folder.name[:8], 16)))
    info = _info(part, mesh, mesh_path)
    _write_record(record, info, float(mesh.volume), hulls, grasps, trials, time.perf_counter() - start)
    return CellPart(info, hulls, grasps, part)


def _hulls(part: MeshPart, mesh_path: Path, folder: Path) -> tuple[Path, ...]:
    from sim.parts.collision import collision_hulls

    return tuple(collision_hulls(mesh_path, folder / "collision"))


def _grasps(part: MeshPart, mesh: trimesh.Trimesh, hulls, rng: np.random.Generator) -> tuple[tuple[Grasp, ...], list]:
    """Grasps from above for each way the part can rest (the upright rest's first), in the model frame, and their
    trials: a part lying any way on the table is grasped by its rest's grasps, those whose approach points down;
    the best of each rest are tried in MuJoCo (:mod:`sim.parts.grasp_trial`) and those that fail dropped."""
    from dataclasses import asdict

    from psorr.synthetic.resting import stable_rests
    from sim.errors import SimInputError
    from sim.parts.grasp_synthesis import synthesise_grasps
    from sim.parts.grasp_trial import verified_grasps

    out, why, trials = [], [], []
    for k, rest in enumerate(_grasped_rests(stable_rests(mesh))):
        posed = mesh.copy()
        posed.apply_transform(rest.T_table_model)
        try:
            found = synthesise_grasps(posed, rng)
        except SimInputError as exc:  # a rest it cannot be grasped in: a pick of a part lying so finds no grasp
            why.append(f"rest {k}: {str(exc).removeprefix('no top-down grasp of the mesh: ')}")
            continue
        R, t = rest.T_table_model[:3, :3].T, -rest.T_table_model[:3, :3].T @ rest.T_table_model[:3, 3]
        found = [Grasp(f"rest{k}_{g.name}", R @ g.point + t, R @ g.approach, R @ g.closing, g.width) for g in found]
        verified = verified_grasps(mesh, hulls, part.density * float(mesh.volume), found, rest.T_table_model)
        trials += [asdict(trial) for trial in verified.trials]
        if not verified.grasps:  # a pick of a part lying so finds no grasp
            why.append(f"rest {k}: none held in MuJoCo ({'; '.join(f'{t.grasp} {t.why}' for t in verified.trials)})")
        out += verified.grasps
    if not out:
        raise PartMeshError(part.path, f"has no grasp from above in any way it rests ({'; '.join(why)})",
                            "choose a part the gripper can hold")
    return tuple(out), trials


def _grasped_rests(rests) -> list:
    """The rests that grasps are synthesised for: the most probable ones that together hold
    ``GRASPED_SHARE`` of the chance, at most ``MAX_GRASPED_RESTS``."""
    share, out = 0.0, []
    for rest in rests[:MAX_GRASPED_RESTS]:
        out.append(rest)
        share += rest.probability
        if share >= GRASPED_SHARE:
            break
    return out


def _info(part: MeshPart, mesh: trimesh.Trimesh, mesh_path: Path) -> WorkpieceInfo:
    from psorr.synthetic.mesh_symmetry import find_symmetries

    symmetry = find_symmetries(mesh)
    color = part.color if part.color is not None else _grey(part.name)
    return WorkpieceInfo(part.name, mesh_path, mass=part.density * float(mesh.volume), color=color,
                         symmetries=symmetry.symmetries, continuous_axis=None)


def _grey(name: str) -> tuple[float, float, float]:
    """A light grey, a little different per name, so that parts tell apart in pictures."""
    shade = int(hashlib.sha256(name.encode()).hexdigest()[:4], 16) / 0xFFFF
    return (0.55 + 0.2 * shade, 0.57 + 0.15 * shade, 0.6 + 0.1 * shade)


def _write_record(path: Path, info: WorkpieceInfo, volume: float, hulls, grasps, trials, seconds: float) -> None:
    record = {
        "name": info.name, "volume": volume, "symmetries": info.symmetries.tolist(),
        "collision_files": [str(h.relative_to(path.parent)) for h in hulls],
        "grasps": [g.as_record() for g in grasps],
        "grasp_trials": trials,
        "seconds": round(seconds, 2), "grasp_params": grasp_settings(),
    }
    write_whole(path, json.dumps(record))


def grasp_settings() -> str:
    """The settings grasps are made with, as text: grasps cached under other settings are made again."""
    from sim.parts.grasp_synthesis import GraspSynthesisParams
    from sim.parts.grasp_trial import GraspTrialParams

    return f"{GraspSynthesisParams()!r} {GraspTrialParams()!r}"


def _read_record(path: Path, part: MeshPart) -> CellPart | None:
    """The cached part, or None when the record is unreadable or names files that are gone."""
    try:
        record = json.loads(path.read_text())
        if record.get("grasp_params") != grasp_settings():  # synthesised with other settings: again
            return None
        hulls = tuple(path.parent / f for f in record["collision_files"])
        grasps = tuple(Grasp.from_record(g) for g in record["grasps"])
        color = part.color if part.color is not None else _grey(part.name)
        info = WorkpieceInfo(part.name, path.with_suffix(".stl"), part.density * float(record["volume"]), color,
                             np.array(record["symmetries"]), None)
    except (OSError, ValueError, KeyError, TypeError, PsorrError):
        return None
    if not info.mesh_path.is_file() or not all(h.is_file() for h in hulls):
        return None
    return CellPart(info, hulls, grasps, part)
