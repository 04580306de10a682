"""Solids for the probe sets (probe_parts.py): boxes and cylinders about the origin, moved, turned and combined
with trimesh's booleans on manifold3d. Lengths in the set's own unit."""

from __future__ import annotations

import numpy as np
import trimesh


def box(x: float, y: float, z: float) -> trimesh.Trimesh:
    """A box of extents (x, y, z), centred on the origin."""
    return trimesh.creation.box((x, y, z))


def cyl(radius: float, height: float, sections: int = 32) -> trimesh.Trimesh:
    """A cylinder about z, centred on the origin, of ``sections`` sides."""
    return trimesh.creation.cylinder(radius=radius, height=height, sections=sections)


def moved(mesh: trimesh.Trimesh, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> trimesh.Trimesh:
    return mesh.copy().apply_translation((x, y, z))


def turned(mesh: trimesh.Trimesh, degrees: float, axis) -> trimesh.Trimesh:
    """``mesh`` turned by ``degrees`` about ``axis`` through the origin."""
    return mesh.copy().apply_transform(trimesh.transformations.rotation_matrix(np.radians(degrees), axis))


def union(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.boolean.union(list(meshes), engine="manifold")


def diff(mesh: trimesh.Trimesh, *cuts: trimesh.Trimesh) -> trimesh.Trimesh:
    """``mesh`` less every one of ``cuts``."""
    return trimesh.boolean.difference([mesh, *cuts], engine="manifold")
