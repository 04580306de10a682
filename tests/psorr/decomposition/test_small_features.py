"""What lets PSORR see small parts: leftover points decomposed finer, bush walls told from bores,
pair lookups that probe the neighbouring angle bins, and vote clusters that straddle a grid border."""

import numpy as np
from scipy.spatial.transform import Rotation

from psorr.decomposition import DecomposeParams, decompose
from psorr.decomposition.detail import decompose_leftovers
from psorr.geometry import shapes
from psorr.hypotheses.pose_clusters import densest_poses, same_pose
from psorr.library.ppf import HashParams, PairTable
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import PrimitiveKind

COARSE = DecomposeParams(voxel_size=0.008)


def _scene(name, seed):
    catalog = load_catalog()
    return workpiece_scene(np.random.default_rng(seed), {name: catalog[name].load_mesh()}, [name])


def _on_part(scene, decomposition):
    """Primitives whose inliers are mostly on the part (ground-truth label 1)."""
    return [p for p in decomposition.primitives if (scene.cloud.labels[p.inliers] == 1).mean() > 0.5]


def test_faces_outward_tells_a_wall_from_a_bore():
    axis_cylinder = (0, 0, 0, 0, 0, 1, 0.01)
    points = np.array([[0.01, 0, 0], [0, 0.02, 0.1]])
    outwards = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    assert shapes.faces_outward(axis_cylinder, points, outwards).all()
    assert not shapes.faces_outward(axis_cylinder, points, -outwards).any()


def test_a_bush_gives_its_outer_wall_not_a_blend_with_its_bore():
    scene = _scene("bushing", 2010)  # upright, seen from above: outer wall r = 15 mm, bore r = 8 mm
    cylinders = [p for p in _on_part(scene, decompose(scene.cloud, COARSE, np.random.default_rng(0)))
                 if p.kind is PrimitiveKind.CYLINDER]
    assert any(abs(c.radius - 0.015) < 0.0015 for c in cylinders), [round(c.radius * 1e3, 1) for c in cylinders]


def test_leftover_pass_finds_a_flat_boards_components():
    scene = _scene("circuit_board", 2031)  # lying flat: the 1.6 mm board is lost in the table
    coarse = decompose(scene.cloud, COARSE, np.random.default_rng(0))
    assert _on_part(scene, coarse) == []
    both = decompose_leftovers(scene.cloud, coarse, 0.005, COARSE, np.random.default_rng(0))
    assert len(_on_part(scene, both)) >= 2
    assert both.primitives[: len(coarse.primitives)] == coarse.primitives
    for index, p in enumerate(both.primitives):
        assert (both.labels[p.inliers] == index).all()
    assert both.stats.total_ms >= coarse.stats.total_ms


def test_lookup_probes_the_neighbouring_bin_across_a_border():
    params = HashParams(angle_step_deg=12.0)
    # A model pair whose three angles sit just below a bin border (35.9 deg: bin 2 ends at 36).
    d = np.radians(35.9)
    n1 = np.array([[np.cos(d), np.sin(d), 0.0]])
    points = np.array([[0, 0, 0], [0.05, 0, 0]], float)
    normals = np.vstack([n1, n1 * [[-1, 1, 1]]])
    table = PairTable.build(params, points, normals, np.zeros(2), np.arange(2), np.array([0]), np.array([1]))
    # The scene sees the pair turned 0.4 deg about z: n1 now at 36.3 deg, across the border.
    R = Rotation.from_euler("z", 0.4, degrees=True).as_matrix()
    scene_n1 = n1 @ R.T
    found, _ = table.lookup(points[:1], scene_n1, points[1:], normals[1:])
    assert len(found) == 1
    strict = PairTable.build(HashParams(nearest_neighbour_bins=False), points, normals, np.zeros(2), np.arange(2),
                             np.array([0]), np.array([1]))
    assert len(strict.lookup(points[:1], scene_n1, points[1:], normals[1:])[0]) == 0
    # ORR asks for its own cell only, whatever the table's default.
    assert len(table.lookup(points[:1], scene_n1, points[1:], normals[1:], neighbours=False)[0]) == 0
    assert len(table.lookup(points[:1], normals[:1], points[1:], normals[1:], neighbours=False)[0]) == 1


def test_a_vote_cluster_straddling_a_cell_border_still_wins():
    rng = np.random.default_rng(0)
    truth = np.eye(4)
    truth[:3, 3] = (0.0199, 0.0, 0.8)  # the model centre sits on a 2 cm cell border in x
    good = np.repeat(truth[None], 9, axis=0)
    good[:, 0, 3] += rng.uniform(-0.003, 0.003, 9)
    # Six chance votes pile into one cell elsewhere; the 9 good ones split about 4 + 5 across x.
    chance = np.repeat(np.eye(4)[None], 6, axis=0)
    chance[:, :3, 3] = (0.31, 0.11, 0.9)
    scattered = np.repeat(np.eye(4)[None], 50, axis=0)
    scattered[:, :3, :3] = Rotation.random(50, random_state=1).as_matrix()
    scattered[:, :3, 3] = rng.uniform(-0.2, 0.2, (50, 3)) + (0, 0, 1.0)
    poses = np.concatenate([scattered, chance, good])
    voters = np.arange(len(poses))  # each pose from its own scene pair
    chosen, _ = densest_poses(poses, np.zeros(len(poses), dtype=np.int64), voters, np.zeros((1, 3)), 0.02, 1)
    assert np.abs(chosen[0, :3, 3] - truth[:3, 3]).max() < 0.004


def test_one_scene_pair_matching_many_model_pairs_is_one_vote():
    truth = np.eye(4)
    truth[:3, 3] = (0.0, 0.0, 0.8)
    agreed = np.repeat(truth[None], 5, axis=0)  # five scene pairs agree on the instance
    echo = np.repeat(np.eye(4)[None], 200, axis=0)  # one pair of parallel faces, matched 200 times
    echo[:, :3, 3] = (0.2, 0.1, 0.9)
    poses = np.concatenate([echo, agreed])
    voters = np.concatenate([np.zeros(200, dtype=np.int64), np.arange(1, 6)])
    chosen, _ = densest_poses(poses, np.zeros(len(poses), dtype=np.int64), voters, np.zeros((1, 3)), 0.02, 1)
    assert np.allclose(chosen[0], truth)


def test_a_cylinder_matches_only_its_own_radius_and_never_a_face():
    from psorr.hypotheses.primitive_match import PrimitiveSizes
    from psorr.library.models import ModelLibrary

    catalog = load_catalog()
    library = ModelLibrary.from_meshes([catalog["bushing"].mesh_path])
    bushing = library.models[0]
    sizes = PrimitiveSizes(library.models)
    own = sizes.compatible(bushing.graph.primitives)  # every primitive could be itself
    assert own[np.arange(len(own)), np.arange(len(own))].all()
    outer = next(k for k, p in enumerate(bushing.graph.primitives)
                 if p.kind is PrimitiveKind.CYLINDER and abs(p.radius - 0.015) < 1e-3)
    bore = next(k for k, p in enumerate(bushing.graph.primitives)
                if p.kind is PrimitiveKind.CYLINDER and abs(p.radius - 0.008) < 1e-3)
    assert not own[outer, bore] and not own[bore, outer]
    planes = [k for k, p in enumerate(bushing.graph.primitives) if p.kind is PrimitiveKind.PLANE]
    assert not own[np.ix_(planes, [outer, bore])].any()  # a face is never a cylinder


def test_same_pose_measures_how_far_apart_two_poses_place_the_points():
    points = np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0], [0.0, 0.03, 0.0]])
    A = np.eye(4)
    shifted = np.eye(4)
    shifted[:3, 3] = [0.0, 0.0, 0.004]  # every point 4 mm away
    turned = np.eye(4)
    turned[:3, :3] = Rotation.from_euler("z", 180, degrees=True).as_matrix()  # 0.1, 0.1 and 0.06 m away
    assert same_pose(points, A, shifted, 0.005) and not same_pose(points, A, shifted, 0.003)
    assert not same_pose(points, A, turned, 0.05) and same_pose(points, A, turned, 0.09)
