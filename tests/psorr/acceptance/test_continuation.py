"""psorr.acceptance.continuation: a pose whose outline the measured surface goes on past sits on a larger object."""

import numpy as np
import trimesh

from psorr.acceptance.continuation import continued_share
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.verification.depth_compare import DepthRenderer
from psorr.verification.scene_view import SceneView


def _block(x: float, y: float, z: float) -> trimesh.Trimesh:
    """A box standing on z = 0, centred on the origin in x and y (metres)."""
    return trimesh.creation.box(extents=(x, y, z)).apply_translation((0, 0, z / 2))


def _samples(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    points, faces = trimesh.sample.sample_surface(mesh, 8000, seed=0)
    return np.asarray(points), mesh.face_normals[faces]


def _renderer(mesh: trimesh.Trimesh) -> DepthRenderer:
    """The mesh's renderer, which gives the check the outline the recognizer gives it."""
    return DepthRenderer(mesh.vertices, mesh.faces)


def test_a_small_block_flush_with_a_large_blocks_side_is_continued_and_alone_is_not():
    small, large = _block(0.08, 0.06, 0.06), _block(0.24, 0.16, 0.06)
    # The small block on the large one's top, flush with its side: the large block's top and side go on past
    # the small one's outline, as a box's faces go on past an L bracket fitted into its corner.
    flush = np.eye(4)
    flush[:3, 3] = (0.0, -0.05, 0.0)
    points, normals = _samples(small)
    # Twice the recognizer's bar (0.1, docs/decisions/0026-continuation-check.md): the flush block is clearly
    # continued, and the lone one clearly not.
    threshold = 0.2
    for seed in range(5):  # the layout's yaw turns the flush side towards the camera or away from it
        on_large = workpiece_scene(np.random.default_rng(seed), {"large": large}, ["large"])
        T = on_large.instances[0].T_camera_model @ flush
        share_on_large = continued_share(SceneView(on_large.cloud), points, normals, T, renderer=_renderer(small))
        alone = workpiece_scene(np.random.default_rng(seed), {"small": small}, ["small"])
        share_alone = continued_share(SceneView(alone.cloud), points, normals, alone.instances[0].T_camera_model,
                                      renderer=_renderer(small))
        assert share_on_large > threshold and share_alone < threshold / 4, (seed, share_on_large, share_alone)


def test_an_l_bracket_in_the_corner_of_a_block_and_the_table_is_continued_past_its_leg():
    """The OSD clouds' commonest false detection: the bracket's inside fitted to a box's face and the table
    in front of it. Past the leg the nearest model points are on its 5 mm top edge, across the box face
    that goes on above; the nearest one alone gave these layouts 0.09-0.11."""
    from psorr import AcceptParams
    from psorr.synthetic.catalog import load_catalog

    bracket = load_catalog()["bracket"].load_mesh()
    points, faces = trimesh.sample.sample_surface(bracket, 8000, seed=0)
    points, normals = np.asarray(points), bracket.face_normals[faces]
    block = _block(0.20, 0.16, 0.12)
    # The leg's inside (x = -25 mm) on the block's +x face, the base's top (z = 5 mm) on the table.
    corner = np.eye(4)
    corner[:3, 3] = (0.10 + 0.025, 0.0, -0.005)
    for seed in (2, 7, 9):  # layouts that turn the block's +x face towards the camera
        scene = workpiece_scene(np.random.default_rng(seed), {"block": block}, ["block"])
        share = continued_share(SceneView(scene.cloud), points, normals, scene.instances[0].T_camera_model @ corner,
                                renderer=_renderer(bracket))
        alone = workpiece_scene(np.random.default_rng(seed), {"bracket": bracket}, ["bracket"])
        share_alone = continued_share(SceneView(alone.cloud), points, normals, alone.instances[0].T_camera_model,
                                      renderer=_renderer(bracket))
        assert share > 1.5 * AcceptParams().max_continued and share_alone < 0.05, (seed, share, share_alone)


def test_a_pose_that_shows_nothing_continues_nothing():
    scene = workpiece_scene(np.random.default_rng(0), {"small": _block(0.08, 0.06, 0.06)}, ["small"])
    behind = np.eye(4)
    behind[2, 3] = -1.0  # behind the camera
    points, normals = _samples(_block(0.08, 0.06, 0.06))
    assert continued_share(SceneView(scene.cloud), points, normals, behind) == 0.0


def test_the_recognizer_drops_a_small_block_found_on_a_large_one_unless_the_check_is_off(tmp_path, monkeypatch):
    from psorr import AcceptParams, ModelLibrary, RecognizeParams, Recognizer

    monkeypatch.setenv("PSORR_CACHE", str(tmp_path / "cache"))
    _block(0.08, 0.06, 0.06).export(tmp_path / "small.stl")
    library = ModelLibrary.from_meshes([tmp_path / "small.stl"])
    unchecked = RecognizeParams(acceptance=AcceptParams(max_continued=None))
    plain, checked = Recognizer(library, params=unchecked), Recognizer(library)
    for seed in (1, 3):  # layouts where the small block's faces fit the large block's top and side
        scene = workpiece_scene(np.random.default_rng(seed), {"large": _block(0.24, 0.16, 0.06)}, ["large"])
        assert plain.recognize(scene.cloud, np.random.default_rng(0)).detections  # a false detection ...
        assert checked.recognize(scene.cloud, np.random.default_rng(0)).detections == ()  # ... that the check drops


def test_beside_an_arm_only_the_outline_in_view_is_read(monkeypatch):
    """Where the arm hides a chassis's outline, the ring there shows the arm, whose surface crosses the planes of
    the chassis's walls. Read whole, the ring puts the true pose over the bar in this layout (of the first 30,
    the one where it does; 0.08 in two more); read where the chassis is measured, it stays well under it."""
    from psorr import AcceptParams
    from psorr.acceptance import continuation
    from psorr.synthetic.catalog import load_catalog

    chassis = load_catalog()["chassis"].load_mesh()
    points, normals = _samples(chassis)
    bar = AcceptParams().max_continued
    for seed in (2,):  # a layout where the arm crosses the chassis's outline
        scene = workpiece_scene(np.random.default_rng(seed), {"chassis": chassis}, ["chassis"], occluder=True)
        view, T = SceneView(scene.cloud), scene.instances[0].T_camera_model
        in_view = continued_share(view, points, normals, T, renderer=_renderer(chassis))
        with monkeypatch.context() as whole_ring:
            whole_ring.setattr(continuation, "_around_measured", lambda view, points, u, v, corner, shape, *_:
                               np.ones(shape, dtype=bool))
            whole = continued_share(view, points, normals, T, renderer=_renderer(chassis))
        assert in_view < bar / 2 < bar < whole, (seed, in_view, whole)


def test_a_large_plate_alone_is_not_continued_by_its_own_face():
    # A 300 x 200 mm plate sampled every 2 mm has more samples than the check tests for what shows; thinned,
    # they left gaps in its silhouette, and its own face seen through them went on past the "outline".
    plate = _block(0.30, 0.20, 0.012)
    points, faces = trimesh.sample.sample_surface(plate, 34000, seed=0)
    points, normals = np.asarray(points), plate.face_normals[faces]
    for seed in range(3):
        scene = workpiece_scene(np.random.default_rng(seed), {"plate": plate}, ["plate"])
        share = continued_share(SceneView(scene.cloud), points, normals, scene.instances[0].T_camera_model)
        assert share < 0.05, (seed, share)


def test_a_thin_plate_on_a_larger_thinner_one_is_continued_and_alone_is_not():
    """A 6 mm plate's pose on a 4 mm plate that is larger all round (a cover clip on another cover). The larger
    plate's top, 4 mm up, lies within the depth tolerance of the small plate's top face: it goes on past the
    outline, and is off the table by the sensor's noise, not by a fixed height (6 mm let these through at
    0.02-0.04). Alone on the table, the plate's own top face's plane takes in the table around it, whose noise
    the bar keeps to a few hundredths."""
    from psorr import AcceptParams

    small, large = _block(0.030, 0.020, 0.006), _block(0.040, 0.030, 0.004)
    points, normals = _samples(small)
    bar = AcceptParams().max_continued
    for seed in range(6):  # cameras 0.70-0.93 m away
        on_large = workpiece_scene(np.random.default_rng(seed), {"large": large}, ["large"])
        share_on_large = continued_share(SceneView(on_large.cloud), points, normals,
                                         on_large.instances[0].T_camera_model, renderer=_renderer(small))
        alone = workpiece_scene(np.random.default_rng(seed), {"small": small}, ["small"])
        share_alone = continued_share(SceneView(alone.cloud), points, normals, alone.instances[0].T_camera_model,
                                      renderer=_renderer(small))
        assert share_on_large > bar and share_alone < bar / 3, (seed, share_on_large, share_alone)
