"""The probe sets from the eighth folder on (probe_parts.py): small fittings, thin covers, parts whose second
moments are round, flat plates, tall and tilted parts, one part in several sizes, and sheets 2-3 mm thick.
Millimetres."""

from __future__ import annotations

import numpy as np
import trimesh
from probe_parts_shapes import box, cyl, diff, moved, turned, union


def small_fittings() -> dict:
    """The eighth folder, 12-24 mm (under the benchmark's 25 mm floor): a nut, a drilled cube, an angle, a spacer,
    a stepped key, a U clip."""
    return {"hex_nut_m8": diff(cyl(13 / np.sqrt(3), 6.5, 6), cyl(4, 10)),
            "drilled_cube": diff(box(20, 20, 20), cyl(3, 30)),
            "small_angle": union(moved(box(22, 15, 3), 0, 0, 1.5), moved(box(3, 15, 18), -9.5, 0, 9)),
            "spacer": diff(cyl(6, 16, 48), cyl(2.5, 20)),
            "stepped_key": union(moved(box(24, 10, 4), 0, 0, 2), moved(box(12, 10, 4), 0, 0, 6)),
            "u_clip": diff(box(18, 10, 14), moved(box(12, 12, 11), 0, 0, 2))}


def thin_covers() -> dict:
    """The ninth folder, covers and plates 3-7 mm as they rest."""
    shell = diff(box(70, 45, 6), moved(box(67, 42, 4.01), 0, 0, -1.0))
    out = {"vented_lid": diff(shell, *[moved(box(30, 3, 4), 5, y, 2) for y in (-8, 0, 8)])}
    legs = [moved(cyl(3, 3, 24), x, y, -1.5) for x in (-24, 24) for y in (-14, 14)]
    out["standoff_cover"] = diff(union(moved(box(60, 40, 4), 0, 0, 2), *legs), moved(cyl(5, 20), 12, 6, 0))
    out["notched_frame"] = diff(box(64, 44, 6), box(50, 30, 10), moved(box(10, 10, 10), 32, 22, 0))
    strip = union(box(80, 30, 5), moved(cyl(5, 2), 28, 0, 3.5))
    out["boss_strip"] = diff(strip, *[moved(cyl(2, 20, 24), x, 0, 0) for x in (-30, -10)])
    bolts = [moved(cyl(2, 20, 24), x, y) for x in (-18, 18) for y in (-18, 18)]
    corner = moved(turned(box(16, 16, 10), 45, (0, 0, 1)), 25, 25, 0)
    out["gasket"] = diff(box(50, 50, 4), cyl(12, 20, 48), *bolts, corner)
    knuckle = moved(turned(cyl(3.5, 35), 90, (1, 0, 0)), -27.5, 0, 3.5)
    out["hinged_door"] = union(moved(box(55, 35, 3), 0, 0, 1.5), knuckle)
    out["lipped_cover"] = union(moved(box(60, 30, 3), 0, 0, 1.5), moved(box(60, 2, 7), 0, 14, 3.5))
    return out


def round_moments() -> dict:
    """The tenth folder: cubes and square sections, whose principal axes say nothing."""
    cut = moved(turned(box(40, 40, 40), 45, (1, -1, 0)), 25, 25, 25)
    flange = union(box(50, 50, 8), moved(cyl(7, 6), 8, 8, 7))
    return {"cube_blind_hole": diff(box(30, 30, 30), moved(cyl(5, 24), 0, 0, 15)),
            "cube_slot": diff(box(28, 28, 28), moved(box(6, 40, 10), 0, 0, 14)),
            "square_bar_cross_hole": diff(box(20, 20, 60), moved(turned(cyl(3, 40), 90, (1, 0, 0)), 0, 0, 15)),
            "square_flange_boss": diff(flange, *[moved(cyl(2.5, 30, 24), x, y) for x in (-18, 18) for y in (-18, 18)]),
            "cube_frame": diff(box(40, 40, 40), box(24, 24, 50), moved(turned(cyl(4, 30), 90, (0, 1, 0)), 15, 0, 0)),
            "chamfered_cube": diff(box(35, 35, 35), cut)}


def flat_plates() -> dict:
    """The eleventh folder: plates 3-6 mm thick cut to outlines."""
    def hole(r, x, y):
        return moved(cyl(r, 40), x, y, 0)
    l_plate = union(moved(box(60, 15, 4), 0, -15, 0), moved(box(15, 45, 4), -22.5, 0, 0))
    corner = moved(turned(box(80, 80, 10), 45, (0, 0, 1)), 40 * np.sqrt(2) / 2, 40 * np.sqrt(2) / 2, 0)
    link = union(box(64, 16, 5), moved(cyl(8, 5, 48), 32, 0, 0), moved(cyl(8, 5, 48), -32, 0, 0))
    crank = union(cyl(10, 6, 48), moved(cyl(7, 6, 48), 50, 0, 0), moved(box(50, 10, 6), 25, 0, 0))
    return {"washer": diff(cyl(20, 3, 64), hole(9, 0, 0)),
            "l_plate": diff(l_plate, hole(2.5, 20, -15), hole(2.5, -22.5, 15)),
            "gusset": diff(box(50, 50, 5), corner, hole(3, -14, -14)),
            "link": diff(link, hole(3, 32, 0), hole(4, -32, 0)),
            "window_cover": diff(box(70, 50, 3), box(30, 20, 10), *[hole(2, x, y) for x in (-30, 30)
                                                                    for y in (-20, 20)]),
            "cross_plate": diff(union(box(60, 14, 6), box(14, 60, 6)), hole(3, 22, 0)),
            "hex_plate": diff(cyl(23, 5, 6), hole(5, 0, 0)),
            "crank": diff(crank, hole(4, 0, 0), hole(3, 50, 0)),
            "comb": union(box(60, 10, 4), *[moved(box(5, 20, 4), x, 15, 0) for x in (-25, -10, 5, 20)]),
            "keyed_disc": diff(cyl(25, 3.5, 64), hole(6, 0, 0), moved(box(6, 8, 10), 0, 22, 0))}


def tall_and_tilted() -> dict:
    """The twelfth folder: parts that stand tall or rest tilted, and one large one."""
    wedge = trimesh.creation.extrude_triangulation(np.array([[0, 0], [60, 0], [0, 25]]), np.array([[0, 1, 2]]), 30)
    wedge = turned(wedge, 90, (1, 0, 0))
    wedge.fix_normals()
    pyramid = trimesh.Trimesh(vertices=[[-20, -20, 0], [20, -20, 0], [20, 20, 0], [-20, 20, 0], [0, 0, 35]],
                              faces=[[0, 2, 1], [0, 3, 2], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    pyramid.fix_normals()
    cone = trimesh.boolean.intersection([trimesh.creation.cone(radius=15, height=100, sections=48),
                                         moved(box(40, 40, 40), 0, 0, 20)], engine="manifold")
    angle = union(moved(box(160, 80, 5), 0, 0, 2.5), moved(box(160, 5, 60), 0, 37.5, 30))
    holes = [moved(cyl(4, 20), x, 0, 0) for x in (-50, 50)]
    holes += [moved(turned(cyl(4, 20), 90, (1, 0, 0)), x, 37.5, 35) for x in (-50, 50)]
    return {"post": union(moved(cyl(8, 80, 48), 0, 0, 40), moved(cyl(15, 5, 48), 0, 0, 2.5)),
            "wedge": wedge,
            "hex_bar": diff(cyl(19 / np.sqrt(3), 60, 6), moved(turned(cyl(3, 40), 90, (1, 0, 0)), 0, 0, 22)),
            "pyramid": pyramid,
            "tapered_sleeve": diff(cone, cyl(5, 100)),
            "large_angle": diff(angle, *holes),
            "handle": union(moved(cyl(5, 40), -40, 0, 20), moved(cyl(5, 40), 40, 0, 20),
                            moved(turned(cyl(5, 90), 90, (0, 1, 0)), 0, 0, 40)),
            "stepped_block": union(moved(box(60, 30, 20), 0, 0, 10), moved(box(40, 30, 20), -10, 0, 30),
                                   moved(box(20, 30, 20), -20, 0, 50)),
            "tube": diff(cyl(15, 60, 64), cyl(13, 70, 64)),
            "tee": union(box(60, 12, 12), moved(box(12, 40, 12), 0, 26, 0))}


def sizes() -> dict:
    """The thirteenth folder: one part in several sizes."""
    def bracket(leg, width=25, t=5):
        body = union(moved(box(leg, width, t), leg / 2, 0, t / 2), moved(box(t, width, leg), t / 2, 0, leg / 2))
        return diff(body, moved(cyl(3, 20), leg * 0.6, 0, 0))
    out = {f"bracket_{leg}": bracket(leg) for leg in (40, 50, 60)}
    out.update({f"spacer_{length}": diff(cyl(10, length, 48), cyl(4, length + 10)) for length in (20, 30, 45)})
    out.update({f"block_60x40x{t}": diff(box(60, 40, t), *[moved(cyl(3, 40), x, 0, 0) for x in (-20, 20)])
                for t in (10, 14)})
    out.update({f"ring_{od}": diff(cyl(od / 2, 10, 64), cyl(od / 4, 20, 48)) for od in (32, 40)})
    return out


def thin_sheets() -> dict:
    """The fifteenth folder: sheets 2-3 mm thick and 28-50 mm long, under a Kinect's per-pixel noise at 0.8 m."""
    def hole(r, x, y):
        return moved(cyl(r, 40), x, y, 0)
    l_sheet = union(moved(box(40, 10, 2), 0, -7.5, 0), moved(box(10, 25, 2), -15, 0, 0))
    notch = moved(box(8, 4, 10), 0, 8, 0)
    return {"cover_30x20": diff(box(30, 20, 2.5), hole(1.6, -10, 0), hole(1.6, 10, 0), notch),
            "l_sheet_40x25": diff(l_sheet, hole(1.6, 12, -7.5)),
            "disc_35": diff(cyl(17.5, 2.5, 64), hole(4, 0, 0), hole(1.6, 11, 0)),
            "tab_28x18": diff(box(28, 18, 2.8), moved(box(6, 6, 10), 14, 9, 0), moved(box(10, 2, 10), -4, 0, 0)),
            "plate_50x30": diff(box(50, 30, 2), *[hole(1.7, x, y) for x in (-20, 20) for y in (-10, 10)],
                                  box(12, 12, 10)),
            "slotted_strip_45x15": diff(box(45, 15, 3), moved(box(20, 4, 10), 5, 0, 0), hole(2, -17, 0))}


MORE_SETS = {"small_fittings": small_fittings, "thin_covers": thin_covers, "round_moments": round_moments,
             "flat_plates": flat_plates, "tall_and_tilted": tall_and_tilted, "sizes": sizes, "thin_sheets": thin_sheets}
