"""A part's convex hull at a pose: where its lowest and highest points are, whatever way it rests."""

from __future__ import annotations

import functools

import numpy as np

from sim.world import World


@functools.lru_cache(maxsize=64)
def _hull_vertices(mesh_path) -> np.ndarray:
    from psorr.io.meshes import read_mesh

    vertices = np.asarray(read_mesh(mesh_path).convex_hull.vertices, dtype=float)
    vertices.setflags(write=False)
    return vertices


def hull_points(world: World, T_world_part: np.ndarray, part: str) -> np.ndarray:
    """(K, 3) the corners of ``part``'s convex hull at the pose (4, 4, world)."""
    return _hull_vertices(world.catalog[part].mesh_path) @ T_world_part[:3, :3].T + T_world_part[:3, 3]


def lowest_point(world: World, T_world_part: np.ndarray, part: str) -> float:
    """World z (m) of ``part``'s lowest point at the pose (4, 4, world)."""
    return float(hull_points(world, T_world_part, part)[:, 2].min())
