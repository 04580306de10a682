"""Folders of parts built for the purpose, each probing one way a user's parts may differ from ours.

The generalization page (docs/benchmarks/generalization.md, "Any folder of parts") reports what the
generalization benchmark gives on each; this script writes them, so those numbers can be checked:

    python benchmarks/probe_parts.py OUT [--set NAME ...]
    python benchmarks/generalization.py --cad OUT/NAME --units mm --split all --clutter 6 --occluded 4

Each set is millimetres but ``centimetres`` (as its name says, in OBJ, PLY and STL). ``small_fittings`` holds
parts under the benchmark's 25 mm floor: run it with ``--min-length 10``. The sets are built with
trimesh's booleans on manifold3d.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import trimesh
from probe_parts_more import MORE_SETS
from probe_parts_shapes import box, cyl, diff, moved, turned, union


def sheet_metal() -> dict:
    """The fifth folder: sheet metal, a washer, a hinge leaf, rounds, a hex standoff, a slotted plate."""
    t = 2.0
    out = {"z_bracket": union(box(30, 40, t), moved(box(t, 40, 25), 15 - t / 2, 0, 12.5 - t / 2),
                              moved(box(30, 40, t), 30 - t, 0, 25 - t))}
    t = 1.5
    u = union(box(50, 30, t), moved(box(t, 30, 20), -25 + t / 2, 0, 10 - t / 2),
              moved(box(t, 30, 20), 25 - t / 2, 0, 10 - t / 2))
    out["u_bracket_holes"] = diff(u, moved(cyl(3, 10), -10), moved(cyl(3, 10), 10))
    out["shell_cover"] = diff(box(60, 40, 15), moved(box(56, 36, 15), 0, 0, -2))
    out["spacer"] = diff(cyl(15, 3, 96), cyl(5, 6, 64))
    leaf = union(box(40, 30, 3), moved(turned(cyl(4, 30, 48), 90, (1, 0, 0)), -20, 0, 2.5))
    out["hinge_leaf"] = diff(leaf, moved(cyl(2, 10, 24), 5, 8), moved(cyl(2, 10, 24), 5, -8),
                             moved(turned(cyl(1.5, 40, 24), 90, (1, 0, 0)), -20, 0, 2.5))
    corners = [trimesh.creation.icosphere(3, 5).apply_translation((x, y, z)).vertices
               for x in (-20, 20) for y in (-10, 10) for z in (-5, 5)]
    out["rounded_block"] = trimesh.convex.convex_hull(np.vstack(corners))
    flats = 10 / np.sqrt(3)
    out["hex_standoff"] = diff(union(cyl(flats, 28, 6), cyl(flats - 0.8, 30, 6)), cyl(2, 40, 32))
    plate = union(box(60, 15, 4), moved(box(15, 40, 4), 0, -27.5))
    slot = union(box(10, 4, 10), moved(cyl(2, 10, 24), -5), moved(cyl(2, 10, 24), 5))
    out["t_plate_slots"] = diff(plate, moved(slot, -18), moved(slot, 18), moved(turned(slot, 90, (0, 0, 1)), 0, -32))
    return out


def machine_elements() -> dict:
    """The sixth folder: a keyed V pulley, a pillow block, a connecting rod, a keyed shaft, a star knob, a gusset
    bracket, a flanged pipe elbow."""
    out = {}
    profile = np.array([(0, 0), (30, 0), (30, 4), (22, 10), (30, 16), (30, 20), (0, 20)], float)
    out["v_pulley"] = diff(trimesh.creation.revolve(profile, sections=96), cyl(5, 50, 48), moved(box(3, 4, 50), 0, 5.5))
    boss = moved(turned(cyl(15, 30, 64), 90, (1, 0, 0)), 0, 0, 16)
    block = union(box(70, 30, 12), moved(box(30, 30, 16), 0, 0, 8), boss)
    bore = moved(turned(cyl(8, 40, 48), 90, (1, 0, 0)), 0, 0, 16)
    out["pillow_block"] = diff(block, bore, moved(cyl(3.5, 40, 24), -27), moved(cyl(3.5, 40, 24), 27))
    rod = union(cyl(14, 8, 64), moved(cyl(9, 8, 48), 100), moved(box(90, 10, 8), 50))
    out["con_rod"] = diff(rod, cyl(8, 20, 48), moved(cyl(5, 20, 32), 100))
    shaft = union(cyl(6, 100, 64), moved(cyl(5, 20, 64), 0, 0, 60))
    out["keyed_shaft"] = diff(shaft, moved(box(4, 4, 30), 0, 5.5, -25))
    lobes = [moved(cyl(6, 10, 48), 14 * np.cos(a), 14 * np.sin(a)) for a in np.radians(np.arange(0, 360, 72))]
    out["star_knob"] = diff(union(cyl(12, 10, 64), *lobes, moved(cyl(8, 8, 48), 0, 0, 9)), cyl(3, 60, 32))
    angle = union(box(50, 30, 5), moved(box(5, 30, 40), -22.5, 0, 17.5))
    rib = moved(trimesh.convex.convex_hull(np.array([[0, -2, 0], [30, -2, 0], [0, -2, 30], [0, 2, 0], [30, 2, 0],
                                                     [0, 2, 30]], float)), -20, 0, 2.5)
    out["gusset_bracket"] = diff(union(angle, rib), moved(cyl(3, 20, 24), 10, 0),
                                 moved(turned(cyl(3, 20, 24), 90, (0, 1, 0)), -22.5, 0, 25))
    bend = trimesh.creation.torus(30, 10, major_sections=64, minor_sections=32)
    outer = trimesh.boolean.intersection([bend, moved(box(60, 60, 40), 30, 30)], engine="manifold")
    elbow = diff(outer, trimesh.creation.torus(30, 8, major_sections=64, minor_sections=32))
    flange = moved(turned(diff(cyl(18, 4, 64), cyl(8, 10, 48)), 90, (1, 0, 0)), 30, 2, 0)
    out["pipe_elbow"] = union(elbow, flange)
    return out


def centimetres() -> dict:
    """The seventh folder, written in centimetres: a motor plate, a finned heat sink, a hub gear, an open
    enclosure, an impeller, a chain link."""
    out = {}
    holes = [cyl(11, 10, 64)] + [moved(cyl(1.6, 10, 24), x, y) for x in (-15.5, 15.5) for y in (-15.5, 15.5)]
    slot = union(box(12, 4, 10), moved(cyl(2, 10, 24), -6), moved(cyl(2, 10, 24), 6))
    out["motor_plate.obj"] = diff(box(60, 60, 4), *holes, moved(slot, 0, 25))
    out["heat_sink.ply"] = union(box(40, 40, 4), *[moved(box(1.5, 40, 20), x, 0, 12) for x in np.linspace(-18, 18, 7)])
    teeth = [turned(moved(box(4, 3, 8), 21, 0), 360 * k / 20, (0, 0, 1)) for k in range(20)]
    out["hub_gear.stl"] = diff(union(cyl(20, 8, 120), *teeth, moved(cyl(8, 10, 64), 0, 0, 9)), cyl(2.5, 60, 32))
    out["enclosure.stl"] = diff(box(80, 50, 30), moved(box(76, 46, 30), 0, 0, 2))
    blades = [turned(turned(moved(box(18, 2, 10), 16, 0), 20, (1, 0, 0)), 60 * k, (0, 0, 1)) for k in range(6)]
    out["impeller.obj"] = diff(union(cyl(8, 12, 64), *blades), cyl(2.5, 40, 32))
    side = union(box(26, 14, 2), moved(cyl(7, 2, 48), -13), moved(cyl(7, 2, 48), 13))
    out["chain_link.stl"] = union(moved(side, 0, 0, -6), moved(side, 0, 0, 6), moved(cyl(3, 14, 32), -13),
                                  moved(cyl(3, 14, 32), 13))
    return {name: mesh.apply_scale(0.1) for name, mesh in out.items()}


SETS = {"sheet_metal": sheet_metal, "machine_elements": machine_elements, "centimetres": centimetres, **MORE_SETS}


def write_set(name: str, folder: Path) -> list[Path]:
    """Build set ``name`` and write its meshes into ``folder`` (STL unless a name carries its format)."""
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for part, mesh in SETS[name]().items():
        if not mesh.is_watertight:
            raise RuntimeError(f"probe set {name}: {part} did not come out closed; its booleans need manifold3d")
        path = folder / (part if "." in part else f"{part}.stl")
        mesh.export(path)
        written.append(path)
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path, help="a folder; each set goes into a folder of its name inside it")
    parser.add_argument("--set", action="append", choices=sorted(SETS), help="a set to write (default: all)")
    args = parser.parse_args(argv)
    for name in args.set or sorted(SETS):
        written = write_set(name, args.out / name)
        units = "cm" if name == "centimetres" else "mm"
        print(f"{name}: {len(written)} parts -> {args.out / name}  (--cad {args.out / name} --units {units})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
