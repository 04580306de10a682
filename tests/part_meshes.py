"""Meshes with known symmetries and classes, built in the tests (metres, closed solids)."""

from __future__ import annotations

import numpy as np
import trimesh


def box(extents=(0.06, 0.04, 0.02)) -> trimesh.Trimesh:
    return trimesh.creation.box(extents)


def cylinder(radius=0.02, height=0.05) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(radius=radius, height=height, sections=64)


def l_bracket(leg_a=0.05, leg_b=0.05, thickness=0.006, width=0.03) -> trimesh.Trimesh:
    """An L profile (legs leg_a along x and leg_b along y, both thickness thick) extruded width along z."""
    t = thickness
    outline = np.array([(0, 0), (leg_a, 0), (leg_a, t), (t, t), (t, leg_b), (0, leg_b)], float)
    caps = [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)]
    n = len(outline)
    vertices = np.vstack((np.column_stack((outline, np.zeros(n))), np.column_stack((outline, np.full(n, width)))))
    faces = [(c, b, a) for a, b, c in caps] + [(a + n, b + n, c + n) for a, b, c in caps]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    mesh = trimesh.Trimesh(vertices, np.array(faces))
    assert mesh.is_watertight and mesh.volume > 0
    return mesh


def plate_with_hole(offset=0.02, thickness=0.006) -> trimesh.Trimesh:
    """An 80 x 50 mm plate, 6 mm thick unless told, with a 12 mm hole through it, ``offset`` from the centre
    along x."""
    plate = trimesh.creation.box((0.08, 0.05, thickness))
    hole = trimesh.creation.cylinder(radius=0.006, height=0.02, sections=48)
    hole.apply_translation((offset, 0.0, 0.0))
    return trimesh.boolean.difference([plate, hole], engine="manifold")


def open_lid(length=0.05, width=0.035, height=0.005, wall=0.0015, floor=0.002) -> trimesh.Trimesh:
    """A shallow open box, as a cover's lid: a ``floor`` thick base and walls ``wall`` thick, ``height`` in all."""
    outer = trimesh.creation.box((length, width, height))
    inner = trimesh.creation.box((length - 2 * wall, width - 2 * wall, height))
    inner.apply_translation((0.0, 0.0, floor))
    return trimesh.boolean.difference([outer, inner], engine="manifold")


def flanged_bushing() -> trimesh.Trimesh:
    """A bushing of radius 15 mm, 40 mm long, with a 6 mm thick flange of radius 30 mm at one end."""
    profile = np.array([(0, 0), (0.03, 0), (0.03, 0.006), (0.015, 0.006), (0.015, 0.04), (0, 0.04)])
    return trimesh.creation.revolve(profile, sections=64)


def ellipsoid() -> trimesh.Trimesh:
    """A smooth ellipsoid of half axes 40, 25 and 15 mm: no plane, no cylinder, no symmetry axis of revolution."""
    return trimesh.creation.icosphere(subdivisions=4, radius=1.0).apply_scale((0.04, 0.025, 0.015))


def spoked_knob(slot_width=0.001) -> trimesh.Trimesh:
    """A knob 8 mm thick: a disc of radius 10 mm with three 10 mm spokes a third of a turn apart, and across its
    top a slot ``slot_width`` wide and 3 mm deep, which alone breaks the three-fold symmetry."""
    parts = [trimesh.creation.cylinder(radius=0.01, height=0.008, sections=64)]
    for k in range(3):
        spoke = trimesh.creation.box((0.012, 0.004, 0.008)).apply_translation((0.014, 0.0, 0.0))
        parts.append(spoke.apply_transform(trimesh.transformations.rotation_matrix(2 * np.pi * k / 3, (0, 0, 1))))
    knob = trimesh.boolean.union(parts, engine="manifold")
    slot = trimesh.creation.box((slot_width, 0.016, 0.006)).apply_translation((0.0, 0.0, 0.004))
    return trimesh.boolean.difference([knob, slot], engine="manifold")


def keyed_pulley() -> trimesh.Trimesh:
    """A V-groove pulley 60 mm across and 20 mm wide, the same both ways up, with a 10 mm bore whose 3 mm
    keyway alone fixes its turn about its axis (z)."""
    profile = np.array([(0, 0), (30, 0), (30, 4), (22, 10), (30, 16), (30, 20), (0, 20)]) * 1e-3
    pulley = trimesh.creation.revolve(profile, sections=96)
    bore = trimesh.creation.cylinder(radius=0.005, height=0.05, sections=48)
    key = trimesh.creation.box((0.003, 0.004, 0.05)).apply_translation((0.0, 0.0055, 0.0))
    return trimesh.boolean.difference([pulley, bore, key], engine="manifold")


def trained_library(parts: dict[str, trimesh.Trimesh], folder):
    """A psorr ModelLibrary trained from ``parts`` (name -> mesh), written as STL files into ``folder``
    (a pytest tmp path), without the training cache."""
    from psorr.library.models import ModelLibrary

    for name, mesh in parts.items():
        mesh.export(folder / f"{name}.stl")
    return ModelLibrary.from_meshes(sorted(folder.glob("*.stl")), use_cache=False)


def drilled_cube(side=0.02, hole_radius=0.003) -> trimesh.Trimesh:
    """A cube with a hole through it along z: its principal moments are all but equal, so its principal axes are
    any three; only the hole tells its turns that take z to x or y from the exact ones."""
    hole = trimesh.creation.cylinder(radius=hole_radius, height=2 * side, sections=32)
    return trimesh.boolean.difference([trimesh.creation.box((side, side, side)), hole], engine="manifold")
