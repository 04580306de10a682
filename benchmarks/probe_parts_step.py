"""Twelve machined parts drawn in a CAD kernel, with fillets and chamfers, written as STEP in millimetres.

The other probe sets (probe_parts.py) are triangle meshes built by booleans; a user's CAD tool draws exact
surfaces, rounds and bevels edges, and exports STEP, which psorr reads through the step extra. This set is
that path end to end (docs/benchmarks/generalization.md, "Any folder of parts"):

    pip install build123d        # the CAD kernel that draws them (OpenCASCADE); not a psorr dependency
    python benchmarks/probe_parts_step.py OUT
    python benchmarks/generalization.py --cad OUT --units mm --split all --clutter 6 --occluded 4
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

try:
    from build123d import (
        Align,
        Axis,
        Box,
        Cylinder,
        GeomType,
        Pos,
        RegularPolygon,
        Rot,
        chamfer,
        export_step,
        extrude,
        fillet,
    )
except ImportError:
    build123d_missing = True
else:
    build123d_missing = False

_BASE = (Align.CENTER, Align.CENTER, Align.MIN) if not build123d_missing else None


def _holes(part, centres, radius: float):
    for x, y in centres:
        part = part - Pos(x, y, 0) * Cylinder(radius, 100)
    return part


def bracket():
    """An L bracket, 70 mm, two 6 mm holes, a 16 mm bore through its wall, its top edges chamfered."""
    part = (Box(70, 40, 6, align=(Align.CENTER, Align.MIN, Align.MIN))
            + Box(70, 6, 40, align=(Align.CENTER, Align.MIN, Align.MIN)))
    part = _holes(part, [(-22, 25), (22, 25)], 3) - Pos(0, 0, 25) * Rot(90, 0, 0) * Cylinder(8, 40)
    return chamfer(part.edges().filter_by(Axis.Y).group_by(Axis.Z)[-1], 1.5)


def flanged_bushing():
    """A bushing with a 60 mm flange, four bolt holes and an 18 mm bore, its top chamfered."""
    part = Cylinder(30, 6, align=_BASE) + Cylinder(15, 30, align=_BASE) - Cylinder(9, 80)
    part = _holes(part, [(22, 0), (-22, 0), (0, 22), (0, -22)], 2.5)
    return chamfer(part.edges().filter_by(GeomType.CIRCLE).group_by(Axis.Z)[-1], 1.0)


def stepped_shaft():
    """A shaft of 20 and 14 mm, 85 mm long, a keyway in its thin end, its thick end chamfered."""
    part = Cylinder(10, 40, align=_BASE) + Pos(0, 0, 40) * Cylinder(7, 45, align=_BASE) - Pos(0, 7, 60) * Box(4, 4, 20)
    return chamfer(part.edges().filter_by(GeomType.CIRCLE).group_by(Axis.Z)[0], 1.0)


def rounded_plate():
    """An 8 mm plate with 8 mm rounded corners, four holes and a rounded pocket."""
    part = _holes(fillet(Box(90, 60, 8).edges().filter_by(Axis.Z), 8), [(35, 20), (-35, 20), (35, -20), (-35, -20)], 3)
    return part - Pos(0, 0, 2) * fillet(Box(40, 25, 6).edges().filter_by(Axis.Z), 4)


def u_channel():
    """A U channel, 80 mm long, its outer bottom edges rounded."""
    part = Box(80, 40, 30) - Pos(0, 0, 4) * Box(82, 30, 30)
    return fillet(part.edges().filter_by(Axis.X).group_by(Axis.Z)[0], 3)


def pillow_block():
    """A pillow block: a 90 mm base with two bolt holes and a boss bored 20 mm."""
    part = Box(90, 30, 10, align=_BASE) + Pos(0, 0, 10) * Box(40, 30, 25, align=_BASE)
    return _holes(part - Pos(0, 0, 25) * Rot(90, 0, 0) * Cylinder(10, 40), [(35, 0), (-35, 0)], 4)


def hex_standoff():
    """A hexagonal standoff, 19 mm across flats and 35 mm long, bored 10 mm, one end chamfered."""
    part = extrude(RegularPolygon(11, 6), 35) - Cylinder(5, 100)
    return chamfer(part.edges().group_by(Axis.Z)[-1], 1.0)


def motor_plate():
    """A 5 mm motor plate, 60 mm square with rounded corners, a 22 mm centre hole and four screw holes."""
    part = fillet(Box(60, 60, 5).edges().filter_by(Axis.Z), 6) - Cylinder(11, 20)
    return _holes(part, [(15.5, 15.5), (-15.5, 15.5), (15.5, -15.5), (-15.5, -15.5)], 1.6)


def knurled_knob():
    """A 36 mm knob with twelve grooves round its rim, a boss and a 6 mm bore."""
    part = Cylinder(18, 16, align=_BASE)
    for k in range(12):
        part = part - Rot(0, 0, 30 * k) * Pos(18, 0, 0) * Cylinder(2.5, 40)
    return part + Pos(0, 0, 16) * Cylinder(8, 10, align=_BASE) - Cylinder(3, 100)


def housing():
    """An open box, 80 x 55 x 35 mm, 3 mm walls, its corners rounded inside and out."""
    outer = fillet(Box(80, 55, 35, align=_BASE).edges().filter_by(Axis.Z), 6)
    return outer - Pos(0, 0, 3) * fillet(Box(74, 49, 40, align=_BASE).edges().filter_by(Axis.Z), 3)


def clamp_block():
    """A split clamp block, 50 mm, bored 16 mm and slit, its bottom edges chamfered."""
    part = Box(50, 30, 25) - Pos(0, 0, 5) * Rot(90, 0, 0) * Cylinder(8, 40) - Pos(0, 0, 10) * Box(2, 40, 20)
    return chamfer(part.edges().group_by(Axis.Z)[0], 1.5)


def spacer_ring():
    """A 44 mm ring, 12 mm thick, bored 28 mm, with a flat on its rim."""
    return Cylinder(22, 12) - Cylinder(14, 40) - Pos(0, -30, 0) * Box(60, 20, 40)


PARTS = {f.__name__: f for f in (bracket, flanged_bushing, stepped_shaft, rounded_plate, u_channel, pillow_block,
                                 hex_standoff, motor_plate, knurled_knob, housing, clamp_block, spacer_ring)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="the folder to write the STEP files into")
    args = parser.parse_args(argv)
    if build123d_missing:
        print("probe_parts_step.py draws its parts with build123d, which is not installed: pip install build123d",
              file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    for name, draw in PARTS.items():
        export_step(draw(), str(args.out / f"{name}.step"))
    print(f"{len(PARTS)} STEP parts in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
