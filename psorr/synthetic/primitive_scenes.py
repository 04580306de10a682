"""Seeded synthetic table-top scenes, ray cast from a Kinect v1 with known surfaces.

The world frame has z up with the table top at z = 0 (look_at, re-exported from
psorr.sensing.camera, builds camera poses). Meshes are trimesh primitives whose
every triangle carries the id of the analytic surface it lies on, so each pixel of a
rendering knows which plane or cylinder it sees. Truths are reported in the camera frame.
The ray caster, render_meshes, lives in psorr.sensing.raycast and is re-exported here.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np
import trimesh

from psorr.errors import InvalidInputError
from psorr.sensing.camera import CameraIntrinsics, depth_to_cloud, look_at
from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise, kinect_noise_with_source
from psorr.sensing.raycast import render_meshes
from psorr.types import PointCloud, PrimitiveKind

MIN_SURFACE_PIXELS = 200
"""A surface is listed in SyntheticScene.surfaces when the clean rendering gives it this many."""
SMALL_SURFACE_LABEL = -2
"""Label of pixels on a surface too small in the image to be listed (-1 is no return)."""
TABLE_EXTENTS = (1.2, 0.8, 0.03)


@dataclass(frozen=True)
class SurfaceTruth:
    """One analytic surface of a synthetic scene, in the camera frame.

    Attributes:
        id: the label its pixels carry.
        kind: PrimitiveKind.PLANE or CYLINDER (compares equal to "plane" / "cylinder").
        params: plane (nx, ny, nz, d), n.x + d = 0, n towards the camera (d > 0);
            cylinder (px, py, pz, ax, ay, az, r): axis point, unit axis, radius; metres.
        name: for example "table_top", "box_top", "box_+x", "boss_side".
    """

    id: int
    kind: PrimitiveKind
    params: tuple[float, ...]
    name: str

    def __post_init__(self):
        object.__setattr__(self, "kind", PrimitiveKind(self.kind))
        object.__setattr__(self, "params", tuple(float(p) for p in self.params))


@dataclass(frozen=True, eq=False)
class SyntheticScene:
    """A rendered scene with its ground truth.

    Attributes:
        cloud: organised (H*W) cloud of the noisy depth in the camera frame; labels are the
            surface id per pixel, -1 without a return, SMALL_SURFACE_LABEL on unlisted surfaces.
        depth_clean, depth: (H, W) metres, noise-free and noisy, 0 without a return.
        surface_ids: (H, W) int64 labels of the clean rendering (same coding as cloud.labels).
        intrinsics: the camera; T_world_camera: (4, 4) camera pose in the world (z up).
        surfaces: the listed surfaces; surfaces[i].id == i.
        adjacent: (i, j), i < j, surfaces that touch along a curve and are seen side by side.
    """

    cloud: PointCloud
    depth_clean: np.ndarray
    depth: np.ndarray
    surface_ids: np.ndarray
    intrinsics: CameraIntrinsics
    T_world_camera: np.ndarray
    surfaces: tuple[SurfaceTruth, ...]
    adjacent: tuple[tuple[int, int], ...]

    def __post_init__(self):
        for name in ("depth_clean", "depth", "surface_ids", "T_world_camera"):
            array = np.array(getattr(self, name))
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    def surface(self, name: str) -> SurfaceTruth:
        """The listed surface called name; raises InvalidInputError if it is not listed."""
        for truth in self.surfaces:
            if truth.name == name:
                return truth
        listed = [s.name for s in self.surfaces]
        raise InvalidInputError(f"no listed surface {name!r}; the listed ones are {listed}")


def _translate(x, y, z) -> np.ndarray:
    return trimesh.transformations.translation_matrix((x, y, z))


def _rotate_z(angle) -> np.ndarray:
    return trimesh.transformations.rotation_matrix(angle, (0.0, 0.0, 1.0))


class _Layout:
    """Meshes in the world frame, each triangle tagged with a named analytic surface."""

    def __init__(self):
        self.meshes: list[tuple[trimesh.Trimesh, np.ndarray]] = []
        self.surfaces: list[tuple[str, str, tuple]] = []  # name, kind, world-frame geometry
        self.touching: list[tuple[str, str]] = []

    def _add(self, name, kind, geometry) -> int:
        self.surfaces.append((name, kind, geometry))
        return len(self.surfaces) - 1

    def add_box(self, name: str, extents, T) -> None:
        """A box of full side lengths extents (3,), centred at T's origin, axes T's columns."""
        mesh = trimesh.creation.box(extents=extents)
        normals = mesh.face_normals
        axis = np.abs(normals).argmax(axis=1)
        sign = np.sign(normals[np.arange(len(normals)), axis])
        face_ids = np.empty(len(normals), dtype=np.int64)
        labels = dict(zip([(0, 1), (0, -1), (1, 1), (1, -1), (2, 1), (2, -1)],
                          ["+x", "-x", "+y", "-y", "top", "bottom"], strict=True))
        for (k, s), label in labels.items():
            n = s * T[:3, k]
            point = T[:3, 3] + n * extents[k] / 2.0
            face_ids[(axis == k) & (sign == s)] = self._add(f"{name}_{label}", "plane", (point, n))
        for (k1, _), l1 in labels.items():
            for (k2, _), l2 in labels.items():
                if k1 < k2:
                    self.touching.append((f"{name}_{l1}", f"{name}_{l2}"))
        self.meshes.append((mesh.apply_transform(T), face_ids))

    def add_cylinder(self, name, radius, height, T, caps=("top", "bottom"), sections=256) -> None:
        """A capped cylinder along T's z axis, centred at T's origin; caps names the +z and
        -z discs."""
        mesh = trimesh.creation.cylinder(radius=radius, height=height, sections=sections)
        nz = mesh.face_normals[:, 2]
        axis = T[:3, 2]
        face_ids = np.full(len(nz), self._add(f"{name}_side", "cylinder", (T[:3, 3], axis, radius)))
        for s, label in zip((1, -1), caps, strict=True):
            point = T[:3, 3] + s * axis * height / 2.0
            face_ids[s * nz > 0.5] = self._add(f"{name}_{label}", "plane", (point, s * axis))
            self.touching.append((f"{name}_side", f"{name}_{label}"))
        self.meshes.append((mesh.apply_transform(T), face_ids))


def _truth_in_camera(kind, geometry, T_camera_world) -> tuple[float, ...]:
    R, t = T_camera_world[:3, :3], T_camera_world[:3, 3]
    if kind == "plane":
        point, normal = geometry
        n = R @ normal
        d = -float(n @ (R @ point + t))
        return (*n, d) if d >= 0 else (*-n, -d)
    point, axis, radius = geometry
    return (*(R @ point + t), *(R @ axis), radius)


def _contacts(ids: np.ndarray) -> Counter:
    """Number of 4-neighbour pixel pairs between each pair of (non-negative) labels."""
    across = np.stack([ids[:, :-1].ravel(), ids[:, 1:].ravel()])
    pairs = np.concatenate([across, np.stack([ids[:-1].ravel(), ids[1:].ravel()])], axis=1)
    pairs = pairs[:, (pairs[0] != pairs[1]) & (pairs.min(axis=0) >= 0)]
    pairs = np.sort(pairs, axis=0)
    keys, counts = np.unique(pairs, axis=1, return_counts=True)
    return Counter({(int(i), int(j)): int(c) for (i, j), c in zip(keys.T, counts, strict=True)})


def _render_scene(layout: _Layout, T_world_camera, rng, noise) -> SyntheticScene:
    intrinsics = CameraIntrinsics.kinect_v1()
    depth_clean, raw = render_meshes(layout.meshes, T_world_camera, intrinsics)
    counts = np.bincount(raw[raw >= 0], minlength=len(layout.surfaces))
    listed = np.flatnonzero(counts >= MIN_SURFACE_PIXELS)
    remap = np.full(len(layout.surfaces), SMALL_SURFACE_LABEL, dtype=np.int64)
    remap[listed] = np.arange(len(listed))
    surface_ids = np.where(raw >= 0, remap[np.maximum(raw, 0)], -1)
    T_camera_world = np.linalg.inv(T_world_camera)
    surfaces = [
        SurfaceTruth(new_id, kind, _truth_in_camera(kind, geometry, T_camera_world), name)
        for new_id, (name, kind, geometry) in enumerate(layout.surfaces[i] for i in listed)
    ]
    by_name = {s.name: s.id for s in surfaces}
    contacts = _contacts(surface_ids)
    pairs = {tuple(sorted((by_name[a], by_name[b]))) for a, b in layout.touching
             if a in by_name and b in by_name}
    adjacent = {pair for pair in pairs if contacts[pair] >= 3}
    if noise is None:
        depth, labels = depth_clean.copy(), surface_ids.copy()
    else:
        depth, source = kinect_noise_with_source(depth_clean, intrinsics, rng, noise)
        labels = np.where(depth > 0, surface_ids.ravel()[source], -1)
    return SyntheticScene(
        cloud=depth_to_cloud(depth, intrinsics, labels=labels),
        depth_clean=depth_clean,
        depth=depth,
        surface_ids=surface_ids,
        intrinsics=intrinsics,
        T_world_camera=T_world_camera,
        surfaces=tuple(surfaces),
        adjacent=tuple(sorted(adjacent)),
    )


def _table_layout() -> _Layout:
    layout = _Layout()
    layout.add_box("table", np.array(TABLE_EXTENTS), _translate(0.0, 0.0, -TABLE_EXTENTS[2] / 2))
    return layout


def _random_camera(rng: np.random.Generator, target) -> np.ndarray:
    """A camera 0.6-0.75 m above the table on its -y side, its optical axis 20-30 deg from
    the vertical, looking at target (put target at y >= 0.05 to keep the eye over the table)."""
    height = rng.uniform(0.6, 0.75)
    tilt = np.radians(rng.uniform(20.0, 30.0))
    azimuth = np.radians(rng.uniform(-10.0, 10.0))
    reach = height * np.tan(tilt)
    eye = np.asarray(target, float) + (reach * np.sin(azimuth), -reach * np.cos(azimuth), height)
    return look_at(eye, target)


def empty_table(rng: np.random.Generator, noise: KinectNoise | None = KINECT_V1) -> SyntheticScene:
    """A bare 1.2 x 0.8 m table top seen from above. rng draws the layout, then the noise."""
    layout = _table_layout()
    T_world_camera = _random_camera(rng, (rng.uniform(-0.1, 0.1), rng.uniform(0.05, 0.15), 0.0))
    return _render_scene(layout, T_world_camera, rng, noise)


def _place_box(layout: _Layout, rng: np.random.Generator, extents) -> np.ndarray:
    """Stand a box on the table at a random spot and heading; returns T_world_box."""
    x, y = rng.uniform(-0.1, 0.1), rng.uniform(0.05, 0.15)
    T_box = _translate(x, y, extents[2] / 2) @ _rotate_z(rng.uniform(0.0, np.pi))
    layout.add_box("box", extents, T_box)
    for side in ("+x", "-x", "+y", "-y", "bottom"):
        layout.touching.append(("table_top", f"box_{side}"))
    return T_box


def box_on_table(rng: np.random.Generator, noise: KinectNoise | None = KINECT_V1) -> SyntheticScene:
    """A box (sides 0.10-0.20 m) on the table, turned by a random angle about the vertical."""
    layout = _table_layout()
    T_box = _place_box(layout, rng, rng.uniform(0.10, 0.20, size=3))
    target = (T_box[0, 3], T_box[1, 3], 0.0)
    return _render_scene(layout, _random_camera(rng, target), rng, noise)


def cylinder_on_table(
    rng: np.random.Generator, noise: KinectNoise | None = KINECT_V1
) -> SyntheticScene:
    """A cylinder (radius 0.03-0.06 m, length 0.15-0.25 m) lying on its side on the table."""
    layout = _table_layout()
    radius, length = rng.uniform(0.03, 0.06), rng.uniform(0.15, 0.25)
    x, y = rng.uniform(-0.1, 0.1), rng.uniform(0.05, 0.15)
    lying = trimesh.transformations.rotation_matrix(np.pi / 2, (0.0, 1.0, 0.0))
    T = _translate(x, y, radius) @ _rotate_z(rng.uniform(0.0, np.pi)) @ lying
    layout.add_cylinder("cylinder", radius, length, T, caps=("cap_a", "cap_b"))
    # The end caps rest on the table too, at the lowest point of each rim.
    layout.touching += [("table_top", "cylinder_side"), ("table_top", "cylinder_cap_a"),
                        ("table_top", "cylinder_cap_b")]
    return _render_scene(layout, _random_camera(rng, (x, y, 0.0)), rng, noise)


def box_with_boss(
    rng: np.random.Generator, noise: KinectNoise | None = KINECT_V1
) -> SyntheticScene:
    """A box (0.12-0.20 x 0.12-0.20 x 0.08-0.14 m) on the table with a short vertical
    cylindrical boss (radius 0.02-0.04 m, height 0.04-0.06 m) standing on its top face."""
    layout = _table_layout()
    extents = np.array([rng.uniform(0.12, 0.20), rng.uniform(0.12, 0.20), rng.uniform(0.08, 0.14)])
    T_box = _place_box(layout, rng, extents)
    radius, height = rng.uniform(0.02, 0.04), rng.uniform(0.04, 0.06)
    room = extents[:2] / 2 - radius - 0.01
    offset = rng.uniform(-room, room)
    T_boss = T_box @ _translate(offset[0], offset[1], extents[2] / 2 + height / 2)
    layout.add_cylinder("boss", radius, height, T_boss)
    layout.touching += [("box_top", "boss_side"), ("box_top", "boss_bottom")]
    target = (T_box[0, 3], T_box[1, 3], 0.0)
    return _render_scene(layout, _random_camera(rng, target), rng, noise)
