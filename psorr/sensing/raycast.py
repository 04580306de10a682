"""Ray casting triangle meshes from a pinhole camera into depth and per-pixel ids.

Shared by the synthetic primitive scenes (psorr.synthetic.primitive_scenes) and the workpiece scenes
(psorr.synthetic.workpiece_scenes): each triangle carries an id, so every pixel knows which surface or
instance it sees.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import open3d as o3d

from psorr.sensing.camera import CameraIntrinsics

if TYPE_CHECKING:
    import trimesh


def render_meshes(
    meshes_with_ids: Sequence[tuple[trimesh.Trimesh, int | np.ndarray]],
    T_world_camera,
    intrinsics: CameraIntrinsics | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Ray cast triangle meshes from a pinhole camera.

    Args:
        meshes_with_ids: (mesh in the world frame, id) pairs; id is one int for the whole
            mesh or an (F,) int array, one per triangle.
        T_world_camera: (4, 4) camera pose, OpenCV axes.
        intrinsics: the camera, Kinect v1 by default.

    Returns:
        (depth, surface_ids): (H, W) float64 z-depth in metres (0 where no hit) and (H, W)
        int64 id of the hit triangle (-1 where no hit). Depth is recomputed in float64 from
        the hit triangle's plane, so it is exact to the mesh.
    """
    intrinsics = intrinsics or CameraIntrinsics()
    T_camera_world = np.linalg.inv(np.asarray(T_world_camera, dtype=np.float64))
    vertices, faces, ids, offset = [], [], [], 0
    for mesh, face_ids in meshes_with_ids:
        v = np.asarray(mesh.vertices, dtype=np.float64)
        f = np.asarray(mesh.faces, dtype=np.int64)
        vertices.append(v @ T_camera_world[:3, :3].T + T_camera_world[:3, 3])
        faces.append(f + offset)
        ids.append(np.broadcast_to(np.asarray(face_ids, dtype=np.int64), (len(f),)))
        offset += len(v)
    h, w = intrinsics.shape
    if not faces:
        return np.zeros((h, w)), np.full((h, w), -1, dtype=np.int64)
    vertices, faces, ids = np.concatenate(vertices), np.concatenate(faces), np.concatenate(ids)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(vertices.astype(np.float32)), o3d.core.Tensor(faces.astype(np.uint32))
    )
    directions = intrinsics.pixel_rays()
    rays = np.concatenate([np.zeros_like(directions), directions], axis=2).astype(np.float32)
    hits = scene.cast_rays(o3d.core.Tensor(rays))
    t_hit = hits["t_hit"].numpy().astype(np.float64)
    hit = np.isfinite(t_hit)
    triangle = hits["primitive_ids"].numpy()[hit].astype(np.int64)
    a, b, c = (vertices[faces[triangle, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    ray = directions[hit]
    along = np.einsum("ij,ij->i", normal, ray)
    exact = np.abs(along) > 1e-6 * np.linalg.norm(normal, axis=1) * np.linalg.norm(ray, axis=1)
    t = t_hit[hit]
    t[exact] = np.einsum("ij,ij->i", normal, a)[exact] / along[exact]
    depth = np.zeros((h, w))
    depth[hit] = t
    surface_ids = np.full((h, w), -1, dtype=np.int64)
    surface_ids[hit] = ids[triangle]
    return depth, surface_ids
