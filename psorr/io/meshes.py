"""Reading triangle meshes (STL, OBJ, PLY, and STEP through :mod:`psorr.io.step`) for training, with the
checks a CAD export needs.

Every failure caused by the file raises CloudFileError naming it and the fix. What is taken but may
not be what the user meant is said (a warning): several meshes in one file, trained as one model,
a mesh turned inside out, trained turned right side out, and a mesh that is not closed.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from psorr.errors import CloudFileError, MissingExtraError
from psorr.io.clouds import require_file, require_suffix
from psorr.io.step import STEP_SUFFIXES, declared_units, is_step, load_step_scene

if TYPE_CHECKING:
    import trimesh

MESH_SUFFIXES = (".stl", ".obj", ".ply") + STEP_SUFFIXES
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
"""Metres per unit of the length units a mesh file may be in (CAD: mostly mm, US CAD often in; some OBJ: cm)."""


def file_units(path, units: str | None) -> str | None:
    """The length unit to read ``path`` in: a STEP file's declared unit (``units``, if given, must agree),
    else ``units`` as given (None: not known)."""
    declared = declared_units(path)
    if declared is None or units is None or units == declared:
        return declared or units
    raise CloudFileError(path, f"declares its lengths in {declared}, but units {units!r} were given",
                         f"give units {declared!r} or none: a STEP file's own unit is used")


def read_mesh(path) -> trimesh.Trimesh:
    """Read a triangle mesh from .stl, .obj, .ply, or .step/.stp (vertices in the file's units; a STEP file's
    are those it declares, :func:`psorr.io.step.declared_units`).

    A file holding several meshes is concatenated into one (trimesh ``force='mesh'``), with a warning that
    names them; an inside-out closed mesh is turned right side out, with a warning.

    Raises:
        CloudFileError: unknown suffix, missing/empty/unparseable file, no faces, or a closed mesh whose
            faces disagree on which way is out.
    """
    import trimesh  # imported here: it is slow to import and only meshes need it

    path = Path(path)
    require_suffix(path, MESH_SUFFIXES, "mesh")
    require_file(path)
    units = declared_units(path)
    try:
        # Unprocessed first: processing drops the faces of NaN or inf vertices without a word.
        scene = load_step_scene(path) if is_step(path) else trimesh.load_scene(path, process=False)
        mesh = _one_mesh(scene)
    except (MissingExtraError, CloudFileError):  # already named the file and the fix
        raise
    except Exception as exc:  # trimesh's many loaders raise many exception types
        raise CloudFileError(path, f"cannot be read as a mesh: {type(exc).__name__}: {exc}",
                             "re-export it as STL, OBJ or PLY") from None
    names = _object_names(path, scene)
    if len(names) > 1:
        warnings.warn(f"{path}: holds {len(names)} meshes ({', '.join(names[:6])}{' ...' if len(names) > 6 else ''}), "
                      f"trained as one model {path.stem!r}; if they are separate parts, export one file per part",
                      stacklevel=2)
    if not isinstance(mesh, trimesh.Trimesh):
        raise CloudFileError(path, f"holds a {type(mesh).__name__}, not one triangle mesh",
                             "export a single mesh")
    broken = int(np.count_nonzero(~np.isfinite(mesh.vertices).all(axis=1)))
    if broken:
        raise CloudFileError(path, f"{broken} of its {len(mesh.vertices)} vertices are NaN or infinite",
                             "repair or re-export the mesh")
    if units is not None:  # OpenCASCADE gives metres
        mesh.apply_scale(1.0 / UNITS[units])
    _merge_duplicate_vertices(path, mesh)
    if len(mesh.faces) == 0:
        if len(mesh.vertices) == 0:
            fix = ("export the part's solid (or its surfaces), not only its edges or points" if is_step(path) else
                   "export the surface as a triangle mesh in the format its suffix names")
            raise CloudFileError(path, f"holds no faces: it is points or lines only, or empty, truncated, or not a "
                                       f"{path.suffix.lower()} file", fix)
        raise CloudFileError(path, "the mesh has no faces",
                             "export the surface, not just its vertices")
    if not mesh.area > 0:  # every triangle degenerate: nothing to sample a surface from
        raise CloudFileError(path, f"the mesh's {len(mesh.faces)} faces have no area",
                             "export the surface; its triangles are collapsed to lines or points")
    return _wound_outward(path, mesh)


def _one_mesh(scene):
    """The scene's meshes, placed and concatenated into one, as trimesh.load(force="mesh") gives them; a scene
    of one mesh gives that mesh, placed, without the two copies that take a third of a large file's read."""
    import trimesh

    nodes = scene.graph.nodes_geometry
    if len(nodes) == 1:
        T, name = scene.graph[nodes[0]]
        mesh = scene.geometry[name]
        if isinstance(mesh, trimesh.Trimesh):
            if not np.array_equal(T, np.eye(4)):
                mesh.apply_transform(T)
            return mesh
    return scene.to_mesh()


def _merge_duplicate_vertices(path: Path, mesh) -> None:
    """Merge the vertices trimesh.load's processing merges (those equal to 1e-8 of the file's unit), in place.

    An STL holds positions only, and repeats each vertex in every face that uses it (six times on a smooth
    part); there trimesh's merge sorts rows of three integers, half a second for a 330,000-face mesh. One
    integer per row, mixed from the three, sorts in half the time; rows that share one but differ are
    checked for, and then trimesh merges. Other formats may carry normals or texture coordinates that keep
    vertices apart: trimesh's processing merges them."""
    from trimesh import util
    from trimesh.constants import tol

    if is_step(path):  # OpenCASCADE gives each face its own vertex normals; the faces meet at the same points
        mesh.merge_vertices(merge_tex=True, merge_norm=True)
        return
    if path.suffix.lower() != ".stl":
        mesh.process()
        return
    referenced = np.zeros(len(mesh.vertices), dtype=bool)
    referenced[mesh.faces] = True
    rows = (mesh.vertices[referenced] * 10.0 ** util.decimal_to_digits(tol.merge)).round().astype(np.int64)
    mixed = rows.view(np.uint64)
    key = (mixed[:, 0] * np.uint64(0x9E3779B97F4A7C15) + mixed[:, 1]) * np.uint64(0xC2B2AE3D27D4EB4F) + mixed[:, 2]
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    if not np.array_equal(rows, rows[first[inverse]]):  # two rows mixed to one integer
        mesh.process()
        return
    order = first.argsort()  # numbered as first met, as trimesh numbers them
    numbering = np.zeros(len(mesh.vertices), dtype=np.int64)
    numbering[referenced] = order.argsort()[inverse]
    normals = mesh.face_normals  # the file's; updating the vertices would recompute them
    mesh.update_vertices(mask=np.flatnonzero(referenced)[first[order]], inverse=numbering)
    mesh.face_normals = normals


def _object_names(path: Path, scene) -> list[str]:
    """The names of the meshes a file holds: trimesh's, or for an OBJ its ``o`` objects, which trimesh's
    loader merges into one mesh unless their materials differ."""
    names = sorted(scene.geometry)
    if path.suffix.lower() == ".obj":
        text = path.read_bytes().decode("utf-8", errors="replace")
        objects = [line[2:].strip() for line in text.splitlines() if line.startswith("o ")]
        if len(objects) > len(names):
            names = objects
    return names


def _wound_outward(path: Path, mesh):
    """``mesh``, turned right side out if it is inside out (said); refused if its faces disagree on which way
    is out. Models take their normals from the winding: an inside-out export (common from CAD) was found
    nowhere, and one with a third of its faces flipped scored lower, without a word. Only a closed mesh has
    an inside to tell outward from (bodies touching along an edge of four faces included:
    :func:`psorr.geometry.solids.is_closed`); an open one is taken as it is, and said."""
    from psorr.geometry.solids import is_closed, open_edges, signed_volume

    if not is_closed(mesh):
        holes = open_edges(mesh)
        if holes == 0:
            raise CloudFileError(path, "its faces disagree on which way is out (some are wound against their "
                                       "neighbours), and a model takes its normals from the winding",
                                 "re-orient the faces coherently (trimesh.repair.fix_normals, or MeshLab's 'Re-Orient "
                                 "all faces coherently') and export it again")
        warnings.warn(f"{path}: the mesh is not closed ({holes} edges border one face or three: a hole's rim or a "
                      "sheet's edge), so nothing tells which way is out: its normals are taken from the faces' "
                      "winding as exported, and a surface "
                      "with no back is trained as it is; export the part as a closed solid (watertight STL) to "
                      "silence this", stacklevel=3)
        return mesh
    if signed_volume(mesh) < 0:
        warnings.warn(f"{path}: the mesh is inside out (every face is wound inward); trained turned right side out; "
                      "re-export it with outward normals to silence this", stacklevel=3)
        mesh = mesh.copy()
        mesh.invert()
    return mesh
