"""The catalog's grasps (sim/skills/grasps.py): read from the workpiece catalog, they fit the gripper, close on
parallel faces and can be reached along their approach; bad grasp entries name the file and the fix."""

import json
from functools import cache

import numpy as np
import pytest
import trimesh

from psorr.errors import InvalidInputError
from psorr.synthetic.catalog import DEFAULT_CATALOG, CatalogError, load_catalog
from sim.errors import GraspCatalogError, SimError
from sim.skills.grasps import Grasp, grasp_named, load_grasps

CATALOG = load_catalog()
NAMES = sorted(CATALOG)
GRASPS_OF = load_grasps()
GRASPS = [(name, g.name) for name in NAMES for g in GRASPS_OF[name]]
# The gripper: a parallel jaw with box fingers; metres.
OPENING = 0.080  # widest finger separation
CLEARANCE = 0.005  # fingers open this far beyond each contact face before closing
FINGER_LENGTH = 0.045  # along the approach, fingertip to palm
FINGER_WIDTH = 0.016  # across both approach and closing
FINGER_THICKNESS = 0.008  # along closing
TIP_PAST_POINT = 0.005  # the pads are centred on the grasp point, so the tips reach this much further


@cache
def _mesh(name: str) -> trimesh.Trimesh:
    return CATALOG[name].load_mesh()


def _first_hits(mesh, origins, direction):
    """(N,) distance from each origin along `direction` to the first surface hit (inf: none), (N, 3) hit normals."""
    origins = np.atleast_2d(origins)
    directions = np.tile(direction, (len(origins), 1))
    locations, rays, triangles = mesh.ray.intersects_location(origins, directions, multiple_hits=True)
    distance = np.full(len(origins), np.inf)
    normal = np.zeros((len(origins), 3))
    for location, ray, triangle in zip(locations, rays, triangles):
        d = float((location - origins[ray]) @ direction)
        if d < distance[ray]:
            distance[ray], normal[ray] = d, mesh.face_normals[triangle]
    return distance, normal


def test_every_catalog_part_has_grasps_with_distinct_names():
    assert sorted(GRASPS_OF) == NAMES
    for name in NAMES:
        names = [g.name for g in GRASPS_OF[name]]
        assert names and len(set(names)) == len(names)


@pytest.mark.parametrize("name", NAMES)
def test_every_part_has_a_grasp_the_gripper_can_hold(name):
    widths = [g.width for g in GRASPS_OF[name]]
    assert max(widths) <= OPENING - 2 * CLEARANCE
    assert any(0.010 <= w <= 0.070 for w in widths)


@pytest.mark.parametrize(("name", "grasp_name"), GRASPS)
def test_grasp_width_is_the_thickness_between_parallel_faces(name, grasp_name):
    mesh, grasp = _mesh(name), grasp_named(name, grasp_name)
    reach = grasp.width / 2 + CLEARANCE
    for side in (1.0, -1.0):
        start = grasp.point + side * reach * grasp.closing
        assert not mesh.contains([start])[0], "the open finger would start inside the part"
        distance, normal = _first_hits(mesh, start, -side * grasp.closing)
        # The contact face sits exactly width / 2 from the point and faces the finger.
        assert distance[0] == pytest.approx(CLEARANCE, abs=1e-5)
        assert normal[0] @ (side * grasp.closing) > 0.999


@pytest.mark.parametrize(("name", "grasp_name"), GRASPS)
def test_grasp_is_reachable_along_its_approach(name, grasp_name):
    mesh, grasp = _mesh(name), grasp_named(name, grasp_name)
    across = np.cross(grasp.approach, grasp.closing)
    reach = grasp.width / 2 + CLEARANCE
    far = 0.5  # start the rays well outside the part
    # Both fingers sweep down to their tips without touching the part...
    for side in (1.0, -1.0):
        tips = np.array(
            [
                grasp.point + side * (reach + t) * grasp.closing + u * across + TIP_PAST_POINT * grasp.approach
                for t in (0.0, FINGER_THICKNESS / 2, FINGER_THICKNESS)
                for u in (-FINGER_WIDTH / 2, 0.0, FINGER_WIDTH / 2)
            ]
        )
        assert np.all(tips[:, 2] >= 0.0), "a fingertip would hit the table"
        distance, _ = _first_hits(mesh, tips - far * grasp.approach, grasp.approach)
        assert np.all(distance > far), "a finger would collide with the part on the way in"
    # ...and nothing of the part between them rises to the palm.
    palm = np.array(
        [
            grasp.point + t * grasp.closing + u * across
            for t in np.linspace(-reach - FINGER_THICKNESS, reach + FINGER_THICKNESS, 9)
            for u in (-FINGER_WIDTH / 2, 0.0, FINGER_WIDTH / 2)
        ]
    )
    distance, _ = _first_hits(mesh, palm - far * grasp.approach, grasp.approach)
    assert np.all(far - distance < FINGER_LENGTH), "the part would hit the palm"


def test_a_grasp_is_read_only_and_checked():
    grasp = GRASPS_OF["chassis"][0]
    assert not grasp.point.flags.writeable and isinstance(grasp.width, float)
    with pytest.raises(InvalidInputError, match="perpendicular"):
        Grasp("g", (0, 0, 0), (0, 0, -1), (0, 0, 1), 0.01)
    with pytest.raises(InvalidInputError, match="unit vector"):
        Grasp("g", (0, 0, 0), (0, 0, -2), (0, 1, 0), 0.01)
    with pytest.raises(InvalidInputError, match="positive"):
        Grasp("g", (0, 0, 0), (0, 0, -1), (0, 1, 0), -0.01)


def test_unknown_names_list_the_valid_choices():
    assert grasp_named("chassis", "across_walls").width == pytest.approx(0.066)
    with pytest.raises(InvalidInputError, match="across_walls"):
        grasp_named("chassis", "sideways")
    with pytest.raises(InvalidInputError, match="flanged_hub"):
        grasp_named("sprocket", "across_walls")


def test_bad_grasp_entries_name_the_file_and_the_fix(tmp_path):
    entry = json.loads(DEFAULT_CATALOG.read_text())["parts"]["bracket"]
    bad = tmp_path / "catalog.json"
    grasp = entry["grasps"][0]
    bad.write_text(json.dumps({"parts": {"bracket": {**entry, "grasps": [{k: v for k, v in grasp.items()
                                                                             if k != "width"}]}}}))
    with pytest.raises(GraspCatalogError, match=r"catalog\.json: a grasp of part 'bracket' lacks the key 'width'"):
        load_grasps(bad)
    bad = tmp_path / "other.json"
    bad.write_text(json.dumps({"parts": {"bracket": {**entry, "grasps": [{**grasp, "closing": [0, 0, 1]}]}}}))
    with pytest.raises(GraspCatalogError, match="perpendicular.*build_workpieces") as info:
        load_grasps(bad)
    assert isinstance(info.value, SimError) and isinstance(info.value, CatalogError)
    with pytest.raises(GraspCatalogError, match="not found"):
        load_grasps(tmp_path / "nowhere.json")
