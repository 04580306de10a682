"""A user's mesh becomes a part of the cell (sim/parts/derive.py), is recognised there and picked. Headless."""

from pathlib import Path

import numpy as np
import pytest
import trimesh

from sim.episode import run_episode
from sim.errors import PartMeshError, SimInputError
from sim.parts.derive import cache_folder, derive_part, upright_mesh
from sim.parts.source import MeshPart
from sim.world import WorldConfig, build_world


def _stepped_block(path):
    """A 70 x 40 x 30 mm block with a 30 x 40 x 15 mm step cut from one end (millimetres), made in the test."""
    block = trimesh.creation.box((70.0, 40.0, 30.0))
    cut = trimesh.creation.box((30.0, 42.0, 16.0))
    cut.apply_translation((20.0, 0.0, 8.0))
    mesh = block.difference(cut)
    mesh.apply_transform(trimesh.transformations.euler_matrix(0.3, 0.2, 0.1))  # not in its resting frame
    mesh.export(path)
    return path


@pytest.fixture(scope="module")
def part(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mesh_part")
    return MeshPart(_stepped_block(folder / "stepped_block.stl"), units="mm", color=(0.8, 0.3, 0.2))


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("PSORR_CACHE", str(tmp_path_factory.mktemp("cache")))
    yield
    mp.undo()


def test_the_mesh_is_turned_to_rest_upright_in_metres(part):
    mesh = upright_mesh(part)
    assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-9)
    assert sorted(np.round(mesh.extents, 4)) == [0.03, 0.04, 0.07]
    assert np.allclose(mesh.bounds.mean(axis=0)[:2], 0.0, atol=0.01)  # the footprint's centre near the origin


def test_a_derived_part_has_mass_hulls_and_grasps_and_is_cached(part, cache):
    derived = derive_part(part, progress=None)
    volume = 70 * 40 * 30 - 30 * 40 * 15
    assert derived.info.mass == pytest.approx(part.density * volume * 1e-9, rel=1e-3)
    assert derived.collision_files and all(f.is_file() for f in derived.collision_files)
    assert derived.grasps and all(g.width < 0.08 for g in derived.grasps)
    assert tuple(derived.info.color) == (0.8, 0.3, 0.2)
    again = derive_part(part, progress=lambda line: pytest.fail(f"derived again: {line}"))
    assert again.collision_files == derived.collision_files
    assert [g.name for g in again.grasps] == [g.name for g in derived.grasps]
    assert np.array_equal(again.info.symmetries, derived.info.symmetries)
    assert cache_folder(part).is_dir()


def test_an_open_mesh_is_refused_with_the_reason(tmp_path):
    box = trimesh.creation.box((40.0, 30.0, 20.0))
    box.update_faces(np.arange(len(box.faces)) != 0)
    box.export(tmp_path / "open.stl")
    with pytest.raises(PartMeshError, match="open.stl: is not closed"):
        upright_mesh(MeshPart(tmp_path / "open.stl", units="mm"))


def test_bodies_touching_along_an_edge_are_a_solid_not_an_open_mesh(tmp_path):
    cube = trimesh.creation.box((30.0, 30.0, 30.0))
    block = trimesh.creation.box((30.0, 60.0, 30.0))
    block.apply_translation((30.0, 45.0, 0.0))  # shares one vertical edge with the cube: four faces border it
    pair = trimesh.util.concatenate([cube, block])
    pair.merge_vertices()
    pair.export(tmp_path / "pair.stl")
    assert not pair.is_watertight
    mesh = upright_mesh(MeshPart(tmp_path / "pair.stl", units="mm"))
    assert mesh.volume == pytest.approx(3 * 27e-6)


def test_a_part_given_in_the_wrong_unit_is_too_small_for_the_sensor(tmp_path):
    trimesh.creation.box((0.04, 0.03, 0.02)).export(tmp_path / "block.stl")  # metres, read as millimetres
    with pytest.raises(PartMeshError, match="too small for the sensor.*is that the file's unit"):
        upright_mesh(MeshPart(tmp_path / "block.stl", units="mm"))


def test_a_step_part_is_read_in_the_unit_it_declares(tmp_path):
    pytest.importorskip("cascadio", reason="the step extra (pip install 'psorr[step]') is not installed")
    step = Path(__file__).parents[2] / "psorr" / "io" / "data" / "bracket_in.step"
    part = MeshPart(step)  # no units: the file's own
    assert part.units == "in"
    assert upright_mesh(part).volume == pytest.approx(20324.56e-9, rel=1e-3)  # the bracket's, in m^3
    with pytest.raises(SimInputError, match="declares its lengths in in, but units 'mm' were given"):
        MeshPart(step, units="mm")
    assert MeshPart(tmp_path / "later.stl").units == "m"  # a file not there yet: said when it is read


def test_the_cell_recognises_and_picks_a_users_part(part, cache):
    config = WorldConfig(workpieces=("stepped_block", "chassis"), mesh_parts=(part,), occluder=False)
    world = build_world(config, np.random.default_rng(4))
    assert world.grasps["stepped_block"] and world.catalog["stepped_block"].mass > 0
    result = run_episode(world, np.random.default_rng(4), poses="recognized")
    pick = next(p for p in result.picks if p.part == "stepped_block")
    assert pick.grasped and pick.placed, pick.note
    assert pick.pose_error_mm < 5.0


def _picks(result):
    return [(p.part, p.grasp_name, p.grasped, p.placed, p.place_error_mm, p.note) for p in result.picks]


def test_two_instances_lying_any_way_and_touching_go_to_the_tote_alike_for_a_seed(part, cache):
    twice = MeshPart(part.path, units="mm", count=2, color=part.color)
    config = WorldConfig(workpieces=("stepped_block",), mesh_parts=(twice,), resting="any", gap=0.0, occluder=False)
    results = []
    for _ in range(2):
        world = build_world(config, np.random.default_rng(11))
        assert world.workpieces == ("stepped_block_1", "stepped_block_2") and world.tote is not None
        assert set(world.places.values()) == {"tote"} and not world.T_world_fixtures
        results.append(run_episode(world, np.random.default_rng(11), poses="oracle"))
    assert _picks(results[0]) == _picks(results[1])
    assert all(p.grasped and p.placed for p in results[0].picks), _picks(results[0])
    for body in world.workpieces:  # in the tote, as the simulator has it
        T_tote_part = np.linalg.inv(world.T_world_tote) @ world.body_pose(body)
        assert np.all(np.abs(T_tote_part[:2, 3]) < world.tote.half_inside)


def test_of_two_instances_in_two_colours_the_robot_picks_the_one_named(part, cache):
    twice = MeshPart(part.path, units="mm", count=2, color=["blue", "red"])
    config = WorldConfig(workpieces=("stepped_block",), mesh_parts=(twice,), occluder=False,
                         pick=("red stepped_block",))
    world = build_world(config, np.random.default_rng(5))
    assert tuple(world.catalog["stepped_block_2"].color) == (0.8, 0.1, 0.1)
    blue_before = world.body_pose("stepped_block_1")
    result = run_episode(world, np.random.default_rng(5), poses="recognized")
    (pick,) = result.picks
    assert pick.part == "stepped_block_2" and pick.grasped and pick.placed, pick.note
    assert np.linalg.norm(world.body_pose("stepped_block_1")[:3, 3] - blue_before[:3, 3]) < 0.005


def test_a_pick_of_a_colour_no_instance_has_is_refused(part, cache):
    config = WorldConfig(workpieces=("stepped_block",), mesh_parts=(part,), occluder=False,
                         pick=("green stepped_block",))
    world = build_world(config, np.random.default_rng(5))
    with pytest.raises(SimInputError, match=r"no stepped_block in green is left to pick.*stepped_block \(red\)"):
        run_episode(world, np.random.default_rng(5), poses="oracle")
