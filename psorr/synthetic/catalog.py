"""The workpiece catalog and the symmetry-aware pose error.

The catalog (assets/workpieces/catalog.json, written by assets/workpieces/build_workpieces.py)
lists every part the cell handles: its CAD mesh, mass, display colour and the
rigid transforms that map the mesh onto itself. Units are metres and kilograms;
transforms are 4x4 arrays in the part's model frame (origin at the centre of the
resting face, +z up). The file also lists each part's gripper grasps, which only
the simulated cell uses and reads itself (sim/skills/grasps.py).
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from psorr.assets import asset_path
from psorr.errors import CloudFileError, InvalidInputError

# The folder comes from the package data, the file is checked when read: a missing catalog gets
# load_catalog's error and its fix rather than failing `import psorr`.
DEFAULT_CATALOG = asset_path("workpieces") / "catalog.json"
CONTINUOUS_STEP_DEG = 2.0  # sampling of rotations about a continuous symmetry axis in symmetric_add
_UNIT_TOL = 1e-6
_REBUILD = "rebuild it with: python assets/workpieces/build_workpieces.py"


class CatalogError(CloudFileError):
    """The workpiece catalog is missing or malformed; the message names the file, the problem and the fix."""


def _vector(value, name: str, shape: tuple[int, ...], unit: bool = False) -> np.ndarray:
    try:
        array = np.array(value, dtype=np.float64, copy=True)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{name} must be numeric: {exc}") from None
    if array.shape != shape or not np.all(np.isfinite(array)):
        raise InvalidInputError(f"{name} must be a finite array of shape {shape}, got shape {array.shape}")
    if unit and abs(np.linalg.norm(array) - 1.0) > _UNIT_TOL:
        raise InvalidInputError(f"{name} must be a unit vector, got length {np.linalg.norm(array):.6g}")
    array.setflags(write=False)
    return array


def _positive(value, what: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if isinstance(value, bool) or not math.isfinite(number) or number <= 0:
        raise InvalidInputError(f"{what} must be a positive number, got {value!r}")
    return number


def _rigid(value, name: str) -> np.ndarray:
    """(4, 4) float64 copy of `value`, checked to be a proper rigid transform."""
    t = _vector(value, name, (4, 4))
    r = t[:3, :3]
    if not np.allclose(t[3], (0, 0, 0, 1)) or not np.allclose(r.T @ r, np.eye(3), atol=1e-6) or np.linalg.det(r) < 0:
        raise InvalidInputError(f"{name} must be a rigid transform (orthonormal rotation, det +1, last row 0 0 0 1)")
    return t


@dataclass(frozen=True, eq=False)
class WorkpieceInfo:
    """One catalog part.

    Attributes:
        name: part name, the catalog key.
        mesh_path: absolute path of the CAD mesh (STL, metres, model frame).
        mass: kilograms.
        color: (3,) display RGB in [0, 1].
        symmetries: (K, 4, 4) model-frame transforms S with S(mesh) = mesh; the first is the identity.
        continuous_axis: (3,) unit direction through the model origin about which the part is a
            surface of revolution, or None.
    """

    name: str
    mesh_path: Path
    mass: float
    color: np.ndarray
    symmetries: np.ndarray
    continuous_axis: np.ndarray | None

    def __post_init__(self):
        object.__setattr__(self, "mesh_path", Path(self.mesh_path))
        object.__setattr__(self, "mass", _positive(self.mass, f"{self.name} mass (kg)"))
        color = _vector(self.color, f"{self.name} color", (3,))
        if color.min() < 0 or color.max() > 1:
            raise InvalidInputError(f"{self.name}: color must be RGB floats in [0, 1]")
        object.__setattr__(self, "color", color)
        symmetries = np.array([_rigid(s, f"{self.name} symmetry {i}") for i, s in enumerate(self.symmetries)])
        if len(symmetries) == 0 or not np.allclose(symmetries[0], np.eye(4)):
            raise InvalidInputError(f"{self.name}: the first symmetry must be the identity")
        symmetries.setflags(write=False)
        object.__setattr__(self, "symmetries", symmetries)
        if self.continuous_axis is not None:
            axis = _vector(self.continuous_axis, f"{self.name} continuous_axis", (3,), True)
            object.__setattr__(self, "continuous_axis", axis)

    def load_mesh(self):
        """The part's trimesh.Trimesh (metres, model frame); CloudFileError if unreadable."""
        from psorr.io.meshes import read_mesh

        return read_mesh(self.mesh_path)

    def bounds(self) -> np.ndarray:
        """(2, 3) read-only model-frame bounds of the mesh (lo, hi), metres; read once per path."""
        return _mesh_bounds(self.mesh_path)


@functools.lru_cache(maxsize=64)
def _mesh_bounds(path: Path) -> np.ndarray:
    from psorr.io.meshes import read_mesh

    bounds = np.asarray(read_mesh(path).bounds, dtype=float)
    bounds.setflags(write=False)
    return bounds


def _parse_part(path: Path, name: str, entry) -> WorkpieceInfo:
    try:
        mesh_path = (path.parent / entry["mesh"]).resolve()
        info = WorkpieceInfo(
            name=name,
            mesh_path=mesh_path,
            mass=entry["mass"],
            color=entry["color"],
            symmetries=entry.get("symmetries", [np.eye(4).tolist()]),
            continuous_axis=entry.get("continuous_axis"),
        )
    except KeyError as exc:
        raise CatalogError(path, f"part {name!r} lacks the key {exc}", _REBUILD) from None
    except (TypeError, InvalidInputError) as exc:
        raise CatalogError(path, f"part {name!r} is malformed: {exc}", _REBUILD) from None
    if not mesh_path.is_file():
        raise CatalogError(path, f"part {name!r} names the mesh {mesh_path}, which does not exist", _REBUILD)
    return info


def load_catalog(path=DEFAULT_CATALOG) -> dict[str, WorkpieceInfo]:
    """Read the workpiece catalog: part name -> WorkpieceInfo (mesh paths resolved against the catalog's folder).

    Raises:
        CatalogError: the file is missing, not JSON, or a part entry is incomplete or invalid.
    """
    path = Path(path)
    if not path.is_file():
        raise CatalogError(path, "catalog file not found", f"check the path, or {_REBUILD}")
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CatalogError(path, f"cannot be read as JSON: {exc}", _REBUILD) from None
    parts = data.get("parts") if isinstance(data, dict) else None
    if not isinstance(parts, dict) or not parts:
        raise CatalogError(path, "has no 'parts' object with at least one part", _REBUILD)
    return {name: _parse_part(path, name, entry) for name, entry in parts.items()}


def get_workpiece(name: str, path=DEFAULT_CATALOG) -> WorkpieceInfo:
    """The catalog entry for `name`; InvalidInputError naming the valid part names if there is none."""
    catalog = load_catalog(path)
    if name not in catalog:
        raise InvalidInputError(f"unknown workpiece {name!r}; choose one of {sorted(catalog)}")
    return catalog[name]


def _axis_rotations(axis: np.ndarray, step_deg: float) -> np.ndarray:
    """(M, 4, 4) rotations about `axis` through the origin, every `step_deg` degrees over a full turn."""
    angles = np.deg2rad(np.arange(0.0, 360.0, step_deg))
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    out = np.tile(np.eye(4), (len(angles), 1, 1))
    out[:, :3, :3] = np.eye(3) + np.sin(angles)[:, None, None] * k + (1 - np.cos(angles))[:, None, None] * (k @ k)
    return out


def symmetry_transforms(info: WorkpieceInfo, step_deg: float = CONTINUOUS_STEP_DEG) -> np.ndarray:
    """(K, 4, 4) model-frame transforms that map the part onto itself: its discrete
    symmetries, each composed with rotations about its continuous axis (if it has one)
    every ``step_deg`` degrees."""
    if info.continuous_axis is None:
        return np.asarray(info.symmetries)
    spins = _axis_rotations(info.continuous_axis, step_deg)
    return np.einsum("kij,mjl->kmil", info.symmetries, spins).reshape(-1, 4, 4)


def symmetric_add(points_model, T_est, T_true, info: WorkpieceInfo) -> float:
    """Symmetry-aware ADD: metres, the mean distance between (N, 3) model points under the
    estimated and the true pose (4x4, model -> world), minimised over the part's symmetries.

    A pose that differs from the truth by a symmetry S (T_est = T_true @ S) scores 0. For a part
    with a continuous axis, rotations about it are also searched, every CONTINUOUS_STEP_DEG degrees.
    """
    points = np.asarray(points_model, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0 or not np.all(np.isfinite(points)):
        raise InvalidInputError(f"points_model must be a finite (N, 3) array with N > 0, got shape {points.shape}")
    T_est = _rigid(T_est, "T_est")
    T_true = _rigid(T_true, "T_true")
    candidates = symmetry_transforms(info)
    est = points @ T_est[:3, :3].T + T_est[:3, 3]
    world = T_true @ candidates  # (K, 4, 4): the true pose composed with each symmetry
    true = np.einsum("nj,kij->kni", points, world[:, :3, :3]) + world[:, None, :3, 3]
    return float(np.linalg.norm(true - est[None], axis=2).mean(axis=1).min())


def model_diameter(mesh) -> float:
    """Metres: the largest distance between two vertices of `mesh` (a trimesh.Trimesh or an (N, 3) array)."""
    from psorr.geometry.diameter import diameter

    vertices = np.asarray(getattr(mesh, "vertices", mesh), dtype=np.float64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 2:
        raise InvalidInputError(f"model_diameter needs at least two 3-D vertices, got shape {vertices.shape}")
    return diameter(vertices)
