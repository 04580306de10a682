"""PSG matching (psorr.hypotheses.cliques and psg): clique features, and a chassis found by method psg."""

from dataclasses import replace

import numpy as np
import pytest

from psorr.decomposition.detail import DetailParams
from psorr.hypotheses.cliques import CliqueKind, cylinder_match, cylinder_poses, graph_cliques
from psorr.hypotheses.corners import CornerIndex
from psorr.hypotheses.edges import EdgeIndex, EdgeSet
from psorr.hypotheses.outline import OutlineParams
from psorr.hypotheses.psg import PsgMatcher, PsgParams, clique_matcher
from psorr.hypotheses.single_cylinder import SingleCylinderParams
from psorr.hypotheses.single_plane import SinglePlaneParams
from psorr.recognize import Recognizer
from psorr.recognize_params import RecognizeParams
from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import Method, OrientedBox, PrimitiveKind, PrimitiveShapeGraph


def _moved(graph: PrimitiveShapeGraph, T: np.ndarray) -> PrimitiveShapeGraph:
    """The graph's primitives carried by the rigid motion T (4, 4)."""
    R, t = T[:3, :3], T[:3, 3]
    prims = []
    for p in graph.primitives:
        if p.kind is PrimitiveKind.PLANE:
            n = R @ p.normal
            params = (*n, p.offset - n @ t)
        else:
            params = (*(R @ p.axis_point + t), *(R @ p.axis), p.radius)
        box = OrientedBox(R @ p.box.center + t, R @ p.box.rotation, p.box.extent)
        prims.append(replace(p, params=tuple(float(v) for v in params), centroid=R @ p.centroid + t, box=box))
    return PrimitiveShapeGraph(tuple(prims), graph.edges)


def _carries(P: np.ndarray, model, scene) -> bool:
    """Does the pose P (4, 4) put each model primitive on its scene primitive (planes: the same plane;
    cylinders: the same axis line), to 1e-3 rad and 0.1 mm? A cylinder standing square on a plane fixes
    no turn about its axis: the pose then takes one from the axis alone, and the plane's normal, a
    few thousandths of a degree off the axis, lands that far off."""
    R, t = P[:3, :3], P[:3, 3]
    for m, s in zip(model, scene):
        if m.kind is PrimitiveKind.PLANE:
            on_plane = R @ (-m.offset * m.normal) + t
            if not (np.allclose(R @ m.normal, s.normal, atol=1e-3) and abs(s.normal @ on_plane + s.offset) < 1e-4):
                return False
        else:
            off_axis = R @ m.axis_point + t - s.axis_point
            if abs(abs(R @ m.axis @ s.axis) - 1) > 1e-6 or np.linalg.norm(np.cross(off_axis, s.axis)) > 1e-4:
                return False
    return True


def _random_motion(rng) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    T[:3, 3] = rng.uniform(-0.5, 0.5, 3)
    return T


@pytest.mark.parametrize("part", ["chassis", "flanged_hub"])
def test_clique_features_are_invariant_to_rigid_motion(library, part):
    graph = library.model(part).graph
    cliques = graph_cliques(graph)
    kinds = {c.kind for c in cliques}
    assert CliqueKind.PLANES in kinds or CliqueKind.PLANE_CYLINDER in kinds
    for seed in range(3):
        T = _random_motion(np.random.default_rng(seed))
        moved = graph_cliques(_moved(graph, T))
        assert [c.vertices for c in moved] == [c.vertices for c in cliques]
        corners = CornerIndex([library.model(part)], [cliques])
        for a, b in zip(cliques, moved):
            assert np.allclose(a.feature, b.feature, atol=1e-6)
            # and the match gives a pose that carries the clique's primitives onto the moved ones
            model = [graph.primitives[k] for k in a.vertices]
            scene = [_moved(graph, T).primitives[k] for k in b.vertices]
            if a.kind is CliqueKind.PLANE_CYLINDER:
                assert cylinder_match(b, a, 1e-3, 1e-6)
                poses = cylinder_poses(scene, model)
            else:
                found = corners.match([b], _moved(graph, T).primitives, 1e-3)
                same_order = (found.model_vertices == np.array(a.vertices)).all(axis=1)
                assert same_order.any()
                poses = list(found.poses[same_order])
            assert any(_carries(P, model, scene) for P in poses)


@pytest.mark.parametrize("method", ["psg", "auto"])
def test_method_psg_finds_a_single_chassis(library, method):
    # The chassis has more primitives than AUTO's bar, so AUTO matches its cliques too.
    assert len(library.model("chassis").graph.primitives) >= PsgParams().auto_primitives
    catalog = load_catalog()
    scene = workpiece_scene(np.random.default_rng(3), {"chassis": catalog["chassis"].load_mesh()}, ["chassis"])
    recognition = Recognizer(library, method).recognize(scene.cloud, np.random.default_rng(0))
    chassis = [d for d in recognition.detections if d.model == "chassis"]
    assert len(chassis) == 1 and len(recognition.detections) == 1
    model = library.model("chassis")
    truth = scene.instances[0].T_camera_model
    assert symmetric_add(model.points, chassis[0].T_cloud_model, truth, catalog["chassis"]) < 0.1 * model.diameter
    assert recognition.stats.method == method and recognition.stats.hypotheses > 0
    # QPBO's nodes are counted, and it left at most all of them undecided.
    assert 0 < recognition.stats.qpbo_nodes and 0 <= recognition.stats.qpbo_unlabelled <= recognition.stats.qpbo_nodes


def test_the_corner_index_finds_the_motion_of_a_moved_model(library):
    models = list(library.models)
    index = CornerIndex(models, [graph_cliques(m.graph) for m in models])
    chassis = [m.name for m in models].index("chassis")
    T = _random_motion(np.random.default_rng(7))
    moved = _moved(library.model("chassis").graph, T)
    corners = [c for c in graph_cliques(moved) if c.kind is CliqueKind.PLANES]
    found = index.match(corners, moved.primitives, 1.0)
    own = found.owners == chassis
    assert own.any()
    # Each scene corner matched in its own vertex order gives the motion itself.
    same = own & (found.scene_vertices == found.model_vertices).all(axis=1)
    assert same.sum() == len(corners)
    assert np.allclose(found.poses[same], T, atol=1e-6)


@pytest.mark.parametrize("part", ["bracket", "u_channel"])
def test_the_edge_index_finds_the_motion_of_a_moved_model_from_two_faces(library, part):
    # Parts seen from above often show two faces and no third that spans space with them; two
    # adjacent faces that are not parallel fix the pose, the faces' middle its place along their line.
    models = list(library.models)
    index = EdgeIndex(models)
    own_index = [m.name for m in models].index(part)
    T = _random_motion(np.random.default_rng(11))
    moved = _moved(library.model(part).graph, T)
    scene = EdgeSet.of(moved)
    assert len(scene) > 0 and np.allclose(scene.angle, EdgeSet.of(library.model(part).graph).angle)
    found = index.match(scene, 1.0)
    same = (found.owners == own_index) & (found.scene_vertices == found.model_vertices).all(axis=1)
    assert same.sum() == len(scene)
    assert np.allclose(found.poses[same], T, atol=1e-6)
    # Matches that break a size rule are dropped before any pose is made.
    nothing = index.match(scene, 1.0, allowed=lambda s, o, m: np.zeros(len(s), dtype=bool))
    assert len(nothing.poses) == 0


def test_what_no_clique_explains_is_paired(library):
    """A pipe tee lying on its pipes rests on a line, so the table makes no clique with it and its faces
    none of their own; the cliques find nothing, and the pair rounds after them find the tee (decision
    0069). Every other stage is off, so only the cliques and the pairs after them search."""
    catalog = load_catalog()
    scene = workpiece_scene(np.random.default_rng(0), {"pipe_tee": catalog["pipe_tee"].load_mesh()}, ["pipe_tee"])
    model, truth = library.model("pipe_tee"), scene.instances[0].T_camera_model

    def found(pairs_after: bool) -> list:
        params = RecognizeParams(psg=PsgParams(pairs_after=pairs_after), outline=OutlineParams(enabled=False),
                                 single_plane=SinglePlaneParams(enabled=False),
                                 single_cylinder=SingleCylinderParams(enabled=False),
                                 detail=DetailParams(fine_voxel=None))
        detections = Recognizer(library, "psg", params).recognize(scene.cloud, np.random.default_rng(0)).detections
        return [symmetric_add(model.points, d.T_cloud_model, truth, catalog["pipe_tee"]) < 0.1 * model.diameter
                for d in detections]

    assert found(pairs_after=False) == []
    assert found(pairs_after=True) == [True]


def test_auto_matches_the_cliques_of_the_models_of_many_primitives_only(library):
    sizes = {m.name: len(m.graph.primitives) for m in library.models}
    bar = sorted(sizes.values())[len(sizes) // 2]  # about half the models at or above it
    auto = clique_matcher(library, Method.AUTO, PsgParams(auto_primitives=bar))
    assert sorted(m.name for m in auto.models) == sorted(n for n, k in sizes.items() if k >= bar)
    assert 0 < len(auto.models) < len(sizes)
    # No model that large: AUTO matches no cliques and is PSORR; PSG matches every model's; PSORR none.
    assert clique_matcher(library, Method.AUTO, PsgParams(auto_primitives=max(sizes.values()) + 1)) is None
    assert len(clique_matcher(library, Method.PSG, PsgParams(auto_primitives=bar)).models) == len(sizes)
    assert clique_matcher(library, Method.PSORR, PsgParams()) is None


def test_a_matcher_of_some_models_names_them_by_their_library_index(library):
    names = [m.name for m in library.models]
    chassis = names.index("chassis")
    scene = _moved(library.model("chassis").graph, _random_motion(np.random.default_rng(5)))
    found = PsgMatcher(library, indexed=[chassis]).candidates(scene, max_extent=1.0).found.candidates
    assert found and {c.model for c in found} == {chassis}


def test_auto_without_a_model_of_many_primitives_is_psorr(library):
    catalog = load_catalog()
    parts = ["chassis", "bracket", "bushing"]
    scene = workpiece_scene(np.random.default_rng(4), {p: catalog[p].load_mesh() for p in parts}, parts)
    none_large = RecognizeParams(psg=PsgParams(auto_primitives=10_000))
    psorr = Recognizer(library, "psorr", none_large).recognize(scene.cloud, np.random.default_rng(0))
    auto = Recognizer(library, "auto", none_large).recognize(scene.cloud, np.random.default_rng(0))
    assert len(psorr.detections) >= 2
    assert [(d.model, d.T_cloud_model.tolist()) for d in auto.detections] == \
        [(d.model, d.T_cloud_model.tolist()) for d in psorr.detections]
    assert auto.stats.hypotheses == psorr.stats.hypotheses and auto.stats.qpbo_nodes == 0
