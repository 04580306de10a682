"""Decomposition of seeded synthetic Kinect scenes against their analytic truth."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from psorr import DecomposeParams, PointCloud, PrimitiveKind, decompose
from psorr.errors import InvalidInputError
from psorr.sensing.camera import depth_to_cloud
from psorr.synthetic import primitive_scenes as synthetic

SEEDS = (0, 1, 2)


def _majority_surface(scene, labels):
    """For each primitive, the truth surface id most of its points hit (or None)."""
    truth = scene.cloud.labels
    out = {}
    for pid in range(labels.max() + 1):
        hit = truth[(labels == pid) & (truth >= 0)]
        out[pid] = int(np.bincount(hit).argmax()) if len(hit) else None
    return out


def _primitive_of(scene, result, surface):
    """The primitive that stands for a truth surface: of those made mostly of
    its points, the one holding most of them; and the share it holds."""
    mine = result.labels[scene.cloud.labels == surface.id]
    majority = _majority_surface(scene, result.labels)
    candidates = [pid for pid, s in majority.items() if s == surface.id]
    if not candidates:
        return None, 0.0
    pid = max(candidates, key=lambda c: (mine == c).sum())
    return pid, float((mine == pid).mean())


# Grazing dropouts can leave a surface that is listed in the clean render with
# a handful of points; nothing can be asked of those.
MIN_NOISY_POINTS = 300


def _check_scene(scene, result):
    matched = {}
    for surface in scene.surfaces:
        if (scene.cloud.labels == surface.id).sum() < MIN_NOISY_POINTS:
            continue
        pid, share = _primitive_of(scene, result, surface)
        assert pid is not None and share > 0.4, f"{surface.name} not recovered (share {share:.2f})"
        prim = result.primitives[pid]
        assert prim.kind is surface.kind, f"{surface.name} came out as a {prim.kind.value}"
        if prim.kind is PrimitiveKind.PLANE:
            normal = np.asarray(surface.params[:3])
            angle = np.degrees(np.arccos(min(1.0, abs(prim.normal @ normal))))
            offset = abs(normal @ prim.centroid + surface.params[3])
            assert angle < 2.0, f"{surface.name}: normal off by {angle:.2f} deg"
            assert offset < 0.002, f"{surface.name}: plane off by {offset * 1e3:.2f} mm"
        else:
            radius = surface.params[6]
            assert abs(prim.radius - radius) < 0.1 * radius, (
                f"{surface.name}: radius {prim.radius * 1e3:.1f} mm, truth {radius * 1e3:.1f} mm")
        matched[surface.id] = pid
    # Every physical contact between visible surfaces is a graph edge (between
    # any of the pieces a surface may be split into, say by a projector shadow) ...
    edges = set(result.graph.edges)
    majority = _majority_surface(scene, result.labels)
    pieces = {s: {p for p, m in majority.items() if m == s} for s in matched}
    for a, b in scene.adjacent:
        if a not in matched or b not in matched:
            continue
        assert any((min(p, q), max(p, q)) in edges for p in pieces[a] for q in pieces[b]), (
            f"missing edge {scene.surfaces[a].name} - {scene.surfaces[b].name}")
    # ... and every edge joins surfaces that touch or whose noise-free points
    # come within the adjacency gap (the PSG's own definition of neighbours).
    allowed = {tuple(sorted(p)) for p in scene.adjacent} | _close_surfaces(scene, ADJACENCY_GAP)
    for i, j in edges:
        si, sj = majority[i], majority[j]
        if si is None or sj is None or si == sj:
            continue
        assert tuple(sorted((si, sj))) in allowed, (
            f"false edge {scene.surfaces[si].name} - {scene.surfaces[sj].name}")


ADJACENCY_GAP = DecomposeParams().adjacency_gap * DecomposeParams().voxel_size


def _close_surfaces(scene, gap):
    clean = depth_to_cloud(scene.depth_clean, scene.intrinsics, labels=scene.surface_ids)
    trees = {s.id: cKDTree(clean.points[clean.labels == s.id]) for s in scene.surfaces}
    close = set()
    for a in scene.surfaces:
        for b in scene.surfaces:
            if a.id < b.id and trees[a.id].sparse_distance_matrix(trees[b.id], gap).nnz:
                close.add((a.id, b.id))
    return close


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("make", [synthetic.box_on_table, synthetic.cylinder_on_table, synthetic.box_with_boss],
                         ids=["box_on_table", "cylinder_on_table", "box_with_boss"])
def test_recovers_truth(make, seed):
    scene = make(np.random.default_rng(seed))
    result = decompose(scene.cloud, rng=np.random.default_rng(seed))
    _check_scene(scene, result)


def test_empty_table_is_one_plane():
    scene = synthetic.empty_table(np.random.default_rng(3))
    result = decompose(scene.cloud)
    assert [p.kind for p in result.primitives] == [PrimitiveKind.PLANE]
    assert result.graph.edges == ()
    assert (result.graph.count(PrimitiveKind.PLANE), result.graph.count(PrimitiveKind.CYLINDER)) == (1, 0)


def test_labels_line_up_with_input_and_nan_points_get_minus_one():
    scene = synthetic.box_on_table(np.random.default_rng(5))
    result = decompose(scene.cloud)
    assert result.labels.shape == (len(scene.cloud),) and result.labels.dtype == np.int64
    assert (result.labels[~scene.cloud.valid_mask] == -1).all()
    for pid, prim in enumerate(result.primitives):
        assert (result.labels[prim.inliers] == pid).all()
        assert np.allclose(prim.centroid, scene.cloud.points[prim.inliers].mean(axis=0))
        # The box holds its inliers (up to float rounding).
        local = (scene.cloud.points[prim.inliers] - prim.box.center) @ prim.box.rotation
        assert (np.abs(local) <= prim.box.extent / 2 + 1e-9).all()


def test_same_seed_same_labels_and_different_seed_still_valid():
    scene = synthetic.box_with_boss(np.random.default_rng(7))
    a = decompose(scene.cloud, rng=np.random.default_rng(11))
    b = decompose(scene.cloud, rng=np.random.default_rng(11))
    assert np.array_equal(a.labels, b.labels)
    assert [p.params for p in a.primitives] == [p.params for p in b.primitives]


def test_unorganised_shuffled_cloud_decomposes_the_same_shapes():
    scene = synthetic.cylinder_on_table(np.random.default_rng(2))
    valid = scene.cloud.valid_mask
    order = np.random.default_rng(0).permutation(int(valid.sum()))
    cloud = PointCloud(scene.cloud.points[valid][order])
    kinds = sorted(p.kind.value for p in decompose(cloud).primitives if p.n_points > 2000)
    assert kinds == ["cylinder", "plane"]


def test_cad_like_cloud_without_sensor_noise_model():
    # Points on a unit-ish box surface, far from any sensor: constant thresholds.
    rng = np.random.default_rng(0)
    faces = []
    for axis in range(3):
        for side in (-0.05, 0.05):
            pts = rng.uniform(-0.05, 0.05, (1500, 3))
            pts[:, axis] = side
            faces.append(pts)
    cloud = PointCloud(np.vstack(faces) + [0, 0, 1.0])
    result = decompose(cloud, DecomposeParams(sensor_noise=False, voxel_size=0.005, min_inlier_distance=0.002))
    planes = [p for p in result.primitives if p.kind is PrimitiveKind.PLANE and p.n_points > 500]
    assert len(planes) == 6
    assert len(result.graph.edges) >= 12  # each face touches four others
    assert result.graph.count(PrimitiveKind.PLANE) + result.graph.count(PrimitiveKind.CYLINDER) == len(result.graph)


def test_bad_inputs_raise_clear_errors():
    with pytest.raises(InvalidInputError, match="PointCloud"):
        decompose(np.zeros((10, 3)))
    with pytest.raises(InvalidInputError, match="finite points"):
        decompose(PointCloud(np.full((50, 3), np.nan)))
    millimetres = PointCloud(synthetic.box_on_table(np.random.default_rng(0)).cloud.points * 1000.0)
    with pytest.raises(InvalidInputError, match=r"decompose\(\): the cloud: .* millimetres: scale it by 0.001"):
        decompose(millimetres)
    with pytest.raises(InvalidInputError, match="voxel_size"):
        DecomposeParams(voxel_size=0)
    with pytest.raises(InvalidInputError, match="cylinder_radius_range"):
        DecomposeParams(cylinder_radius_range=(0.2, 0.1))


@pytest.mark.parametrize("bad", [5, np.random.RandomState(0)])
def test_rng_must_be_a_generator_and_the_error_says_how_to_make_one(bad):
    scene = synthetic.box_on_table(np.random.default_rng(0))
    with pytest.raises(InvalidInputError, match=r"decompose\(\) takes rng=np.random.default_rng"):
        decompose(scene.cloud, rng=bad)


def test_voxels_survive_a_stray_point_and_a_tiny_voxel():
    # Far points and tiny voxels made the flat voxel key overflow int64 ("'minlength' must not be negative").
    from psorr.decomposition.preprocess import voxel_downsample

    rng = np.random.default_rng(0)
    points = rng.uniform(0, 0.1, (500, 3)) + [0, 0, 1]
    centroids, voxel_of = voxel_downsample(points, 0.01)
    stray = np.vstack([points, [[3e4, -2e4, 5e4]]])
    far_centroids, far_voxel_of = voxel_downsample(stray, 0.01)
    assert len(far_centroids) == len(centroids) + 1 and np.allclose(far_centroids[far_voxel_of[-1]], stray[-1])
    # Same grouping as without the stray point.
    assert len(np.unique(np.column_stack([voxel_of, far_voxel_of[:-1]]), axis=0)) == len(centroids)
    tiny_centroids, tiny_voxel_of = voxel_downsample(points, 1e-9)  # one voxel per point
    assert len(tiny_centroids) == len(points) and np.allclose(tiny_centroids[tiny_voxel_of], points)
