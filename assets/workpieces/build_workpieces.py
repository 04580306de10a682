"""Build the workpiece CAD meshes and their catalog.

Run from the repository root:

    .venv/bin/python assets/workpieces/build_workpieces.py [--png assets/workpieces/workpieces.png]

Writes binary STL files in metres to assets/workpieces/meshes/<name>.stl and
assets/workpieces/catalog.json. Geometry is designed in millimetres (so the
numbers below read like a drawing) and scaled to metres on output. Model frame
of every part: origin at the centre of its resting face, +z up, so the part
rests on a table at identity. The output is deterministic byte for byte.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import manifold3d as m3
import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # solids.py beside this script, however it is run or loaded
from solids import COS_HALF, MM, N_HOLE, _along, _box, _circle, _cut, _cyl, _prism, _rot, _union  # noqa: E402

DENSITY = {"steel": 7850.0, "aluminium": 2700.0, "fr4": 1850.0}  # kg/m^3


@dataclass(frozen=True)
class Part:
    """One built workpiece: the mesh in metres and its catalog entry (metres, kg)."""

    name: str
    mesh: trimesh.Trimesh
    material: str
    color: tuple[float, float, float]
    symmetries: tuple[np.ndarray, ...]
    continuous_axis: tuple[float, float, float] | None
    grasps: tuple[dict, ...]


# ---------------------------------------------------------------- catalog entries (mm)


def _grasp(name, point_mm, closing, width_mm, approach=(0.0, 0.0, -1.0)):
    return {
        "name": name,
        "point": [round(c * MM, 9) for c in point_mm],
        "approach": [float(c) for c in approach],
        "closing": [float(c) for c in closing],
        "width": round(width_mm * MM, 9),
    }


# ---------------------------------------------------------------- parts (mm)


def _chassis():
    """Folded aluminium tray 140 x 66 x 40 with 1.5 mm walls and bottom mounting feet."""
    t = 1.5
    tray = _cut(_box((-70, -33, 0), (70, 33, 40)), _box((-70 + t, -33 + t, t), (70 - t, 33 - t, 41)))
    feet = _box((-60, -45, 0), (60, 45, t))
    holes = [_cyl(2.25, -1, 3, x, y, N_HOLE) for x in (-45, 0, 45) for y in (-39, 39)]
    holes += [_cyl(1.75, -1, 3, x, y, N_HOLE) for x in (-55, 55) for y in (-22, 22)]
    window = _box((66, -15, 12), (72, 15, 30))  # connector cut-out in the +x end wall
    gland = _along(_cyl(6.0, -72, -66, 15, 22, N_HOLE), "x")  # cable gland hole, -x end wall
    shape = _cut(_union(tray, feet), *holes, window, gland)
    grasps = (
        _grasp("across_walls", (0, 0, 25), (0, 1, 0), 66.0),
        _grasp("end_wall_pinch", (-70 + t / 2, -15, 30), (1, 0, 0), t),
        _grasp("side_wall_pinch", (20, 33 - t / 2, 30), (0, 1, 0), t),
    )
    return shape, "aluminium", (0.72, 0.74, 0.78), (np.eye(4),), None, grasps


def _transformer():
    """E-I core 70 x 25 x 60 with a primary and a secondary coil stacked on the centre limb."""
    core = _cut(
        _box((-35, -12.5, 0), (35, 12.5, 60)), _box((-25, -13, 10), (-10, 13, 50)), _box((10, -13, 10), (25, 13, 50))
    )
    r = 24.0  # clears the outer limbs (inner faces at |x| = 25) and encloses the 20 x 25 centre limb
    shape = _union(core, _cyl(r, 11, 29.5), _cyl(r, 30.5, 49))
    grasps = (
        _grasp("outer_limb_pos_x", (30, 0, 40), (0, 1, 0), 25.0),
        _grasp("outer_limb_neg_x", (-30, 0, 40), (0, 1, 0), 25.0),
        _grasp("across_coils", (0, 0, 20), (0, 1, 0), 2 * r * COS_HALF),
    )
    symmetries = (np.eye(4), _rot((0, 0, 1), 180), _rot((1, 0, 0), 180, (0, 0, 30)), _rot((0, 1, 0), 180, (0, 0, 30)))
    return shape, "steel", (0.55, 0.30, 0.18), symmetries, None, grasps


def _circuit_board():
    """FR4 board 100 x 70 x 1.6 with a terminal block, two ICs and three electrolytic capacitors."""
    b = 1.6
    board = _cut(
        _box((-50, -35, 0), (50, 35, b)), *[_cyl(1.6, -1, 3, x, y, N_HOLE) for x in (-45, 45) for y in (-30, 30)]
    )
    pitch = (-16.5, -5.5, 5.5, 16.5)
    terminal = _cut(
        _box((-22, 22, b), (22, 33, b + 14)),
        *[_cyl(1.6, b + 9, b + 15, x, 26, N_HOLE) for x in pitch],  # screw access
        *[_box((x - 2.5, 28, b + 4), (x + 2.5, 34, b + 9)) for x in pitch],  # wire entries on the +y face
    )
    ics = [_box((-40, -8, b), (-10, 6, b + 8)), _box((-5, -6, b), (15, 6, b + 8))]
    caps = [_cyl(6.5, b, b + 20, 32, -18), _cyl(5.0, b, b + 13, 38, 12), _cyl(4.0, b, b + 11, -38, -24)]
    shape = _union(board, terminal, *ics, *caps)
    grasps = (
        _grasp("terminal_block", (0, 27.5, b + 8.4), (0, 1, 0), 11.0),
        _grasp("big_capacitor", (32, -18, b + 12), (1, 0, 0), 13.0 * COS_HALF),
    )
    return shape, "fr4", (0.10, 0.45, 0.20), (np.eye(4),), None, grasps


def _bracket():
    """Aluminium L-bracket: 60 x 40 x 5 base with two slots, 50 mm leg with two holes."""
    base = _box((-30, -20, 0), (30, 20, 5))
    leg = _box((-30, -20, 0), (-25, 20, 50))
    slots = [m3.Manifold.batch_hull([_cyl(3.25, -1, 6, x, y, N_HOLE) for x in (4, 16)]) for y in (-10, 10)]
    holes = [_along(_cyl(3.25, -31, -24, y, 32, N_HOLE), "x") for y in (-12, 12)]
    shape = _cut(_union(base, leg), *slots, *holes)
    grasps = (
        _grasp("leg_across", (-27.5, 0, 30), (0, 1, 0), 40.0),
        _grasp("leg_pinch", (-27.5, 0, 42), (1, 0, 0), 5.0),
    )
    return shape, "aluminium", (0.35, 0.55, 0.85), (np.eye(4),), None, grasps


def _flanged_hub():
    """Steel hub: flange D80 x 10, hub D40 to 50 mm height, D20 bore, six D8 bolt holes on a D60 circle."""
    bolt = _circle(4.0, N_HOLE, 30.0, 0.0)
    holes = []
    for k in range(6):
        # Rotating the points (not placing a new circle) keeps the pattern exactly 6-fold symmetric.
        a = math.radians(60 * k)
        rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        holes.append(_prism(bolt @ rot.T, -1, 11))
    shape = _cut(_union(_cyl(40, 0, 10), _cyl(20, 0, 50)), _cyl(10, -1, 51), *holes)
    symmetries = tuple(_rot((0, 0, 1), 60 * k) for k in range(6))
    grasps = (
        _grasp("hub_x", (0, 0, 35), (1, 0, 0), 40 * COS_HALF),
        _grasp("hub_y", (0, 0, 35), (0, 1, 0), 40 * COS_HALF),
    )
    return shape, "steel", (0.45, 0.47, 0.52), symmetries, None, grasps


def _u_channel():
    """Steel U-profile 120 long, 50 wide, 30 high, 4 mm thick, with web and flange holes."""
    channel = _cut(_box((-60, -25, 0), (60, 25, 30)), _box((-61, -21, 4), (61, 21, 31)))
    web_holes = [_cyl(4.5, -1, 5, x, 0, N_HOLE) for x in (-40, 40)]
    wall_holes = [_along(_cyl(3.5, -26, 26, 18, x, N_HOLE), "y") for x in (-30, 30)]
    shape = _cut(channel, *web_holes, *wall_holes)
    grasps = (
        _grasp("across_walls", (0, 0, 20), (0, 1, 0), 50.0),
        _grasp("wall_pinch", (0, 23, 20), (0, 1, 0), 4.0),
    )
    return shape, "steel", (0.55, 0.32, 0.72), (np.eye(4), _rot((0, 0, 1), 180)), None, grasps


def _pipe_tee():
    """Equal steel tee, OD 42 / ID 35, run 110 along x, branch 55 along +y, lying flat on the table."""
    r, ri = 21.0, 17.5
    h = r * COS_HALF  # axis height: the bottom facets rest on the table
    outer = _union(_along(_cyl(r, -55, 55), "x"), _along(_cyl(r, 0, 55), "y"))
    inner = _union(_along(_cyl(ri, -56, 56), "x"), _along(_cyl(ri, 0, 56), "y"))
    shape = (outer - inner).translate((0.0, 0.0, h))
    grasps = (
        _grasp("run_neg_x", (-38, 0, h), (0, 1, 0), 2 * h),
        _grasp("run_pos_x", (38, 0, h), (0, 1, 0), 2 * h),
        _grasp("branch", (0, 38, h), (1, 0, 0), 2 * h),
    )
    return shape, "steel", (0.80, 0.45, 0.10), (np.eye(4), _rot((0, 1, 0), 180, (0, 0, h))), None, grasps


def _bushing():
    """Steel flanged bushing: flange D50 x 6, body D30 to 36 mm height, D16 bore (a surface of revolution)."""
    shape = _cut(_union(_cyl(25, 0, 6), _cyl(15, 0, 36)), _cyl(8, -1, 37))
    grasps = (_grasp("body", (0, 0, 25), (1, 0, 0), 30 * COS_HALF),)
    return shape, "steel", (0.75, 0.65, 0.20), (np.eye(4),), (0.0, 0.0, 1.0), grasps


BUILDERS = {
    "chassis": _chassis,
    "transformer": _transformer,
    "circuit_board": _circuit_board,
    "bracket": _bracket,
    "flanged_hub": _flanged_hub,
    "u_channel": _u_channel,
    "pipe_tee": _pipe_tee,
    "bushing": _bushing,
}


# ---------------------------------------------------------------- build and write


def _to_trimesh(name, solid):
    solid = solid.scale((MM, MM, MM))
    out = solid.to_mesh64()
    mesh = trimesh.Trimesh(np.asarray(out.vert_properties)[:, :3], np.asarray(out.tri_verts), process=False)
    problems = {
        "not watertight": not mesh.is_watertight,
        "inconsistent winding": not mesh.is_winding_consistent,
        "non-positive volume": mesh.volume <= 0,
        f"{mesh.body_count} bodies": mesh.body_count != 1,
    }
    if any(problems.values()):
        raise RuntimeError(f"{name}: " + ", ".join(text for text, bad in problems.items() if bad))
    return mesh


def build_parts() -> dict[str, Part]:
    """Build every workpiece in memory (no files written); metres, model frame as in the module docstring."""
    parts = {}
    for name, builder in BUILDERS.items():
        solid, material, color, symmetries, axis, grasps = builder()
        parts[name] = Part(name, _to_trimesh(name, solid), material, color, symmetries, axis, grasps)
    return parts


def _catalog_entry(part: Part) -> dict:
    density = DENSITY[part.material]
    return {
        "mesh": f"meshes/{part.name}.stl",
        "material": part.material,
        "density": density,
        "mass": round(float(part.mesh.volume) * density, 6),
        "extents": [round(float(e), 6) for e in part.mesh.extents],
        "color": list(part.color),
        "symmetries": [np.round(s, 12).tolist() for s in part.symmetries],
        "continuous_axis": list(part.continuous_axis) if part.continuous_axis else None,
        "grasps": list(part.grasps),
    }


def write_all(out_dir: Path = HERE) -> dict[str, Part]:
    """Build every part, write meshes/<name>.stl (binary, metres) and catalog.json under `out_dir`."""
    parts = build_parts()
    (out_dir / "meshes").mkdir(parents=True, exist_ok=True)
    for part in parts.values():
        (out_dir / "meshes" / f"{part.name}.stl").write_bytes(part.mesh.export(file_type="stl"))
    catalog = {
        "units": "metres, kilograms; poses and symmetries are 4x4 model-frame transforms",
        "model_frame": "origin at the centre of the resting face, +z up; the part rests on a table at identity",
        "parts": {name: _catalog_entry(part) for name, part in parts.items()},
    }
    text = json.dumps(catalog, indent=1)
    # One line per vector or matrix row keeps the catalog readable (a 4x4 would otherwise take 24 lines).
    text = re.sub(r"\[\s+([^\[\]{}]*?)\s+\]", lambda m: "[" + re.sub(r",\s+", ", ", m.group(1)) + "]", text)
    (out_dir / "catalog.json").write_text(text + "\n")
    return parts


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE, help="output directory (default: next to this script)")
    parser.add_argument("--png", type=Path, help="also render an overview sheet of all parts to this PNG")
    args = parser.parse_args(argv)
    parts = write_all(args.out)
    for part in parts.values():
        size = " x ".join(f"{e * 1000:.1f}" for e in part.mesh.extents)
        print(f"{part.name:14s} {size:>22s} mm  {len(part.mesh.faces):6d} triangles")
    if args.png:
        sys.path.insert(0, str(HERE))  # the sibling module, also when this file was imported rather than run
        from render_sheet import render_sheet  # matplotlib is only needed for the picture

        render_sheet(parts, args.png)
        print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
