"""psorr.synthetic.part_shapes: the class of meshes built here, whose class is known."""

from __future__ import annotations

import pytest
from part_meshes import box, cylinder, ellipsoid, flanged_bushing, l_bracket, plate_with_hole

from psorr.errors import InvalidInputError
from psorr.synthetic.part_shapes import PartClass, part_shape

pytest.importorskip("networkx", reason="trimesh's stable poses need networkx (pip install networkx)")


@pytest.mark.parametrize(("mesh", "expected"), [
    (plate_with_hole(), PartClass.THIN),             # 6 mm as it rests
    (box((0.08, 0.05, 0.008)), PartClass.THIN),      # 8 mm is thin still
    (box((0.08, 0.05, 0.01)), PartClass.PRISMATIC),
    (l_bracket(), PartClass.PRISMATIC),
    (cylinder(), PartClass.TURNED),
    (flanged_bushing(), PartClass.FLANGED),
    (ellipsoid(), PartClass.FREEFORM),
])
def test_parts_of_known_kind_are_classed_so(mesh, expected):
    assert part_shape(mesh).part_class is expected


def test_the_measures_say_why():
    bushing = part_shape(flanged_bushing())
    assert bushing.continuous_axis and bushing.flanged and bushing.revolution_share == pytest.approx(1.0, abs=0.01)
    plate = part_shape(box((0.08, 0.05, 0.01)))
    assert plate.primitive_share == pytest.approx(1.0) and plate.side_share < 0.25 and not plate.continuous_axis
    assert plate.resting_height == pytest.approx(0.01)
    assert part_shape(ellipsoid()).primitive_share < 0.1


def test_bad_input_says_what_to_give():
    with pytest.raises(InvalidInputError, match="trimesh.Trimesh"):
        part_shape("part.stl")
