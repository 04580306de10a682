"""psorr.verification.depth_compare: the pixels a render-and-compare search looks at."""

import numpy as np
import trimesh

from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.verification.depth_compare import DepthRenderer, footprint, pixel_window
from psorr.verification.scene_view import SceneView


def test_a_footprint_holds_every_pixel_the_model_renders_in():
    # Pixels outside it render the bare table for every pose, so leaving them out changes no choice; a
    # pixel the model covers but the footprint missed would.
    part = trimesh.creation.box(extents=(0.12, 0.04, 0.02)).apply_translation((0, 0, 0.01))
    scene = workpiece_scene(np.random.default_rng(0), {"part": part}, ["part"])
    view, T = SceneView(scene.cloud), scene.instances[0].T_camera_model
    points, _ = trimesh.sample.sample_surface(part, 3000, seed=0)
    spacing = np.sqrt(part.area / len(points))
    turns = [T @ trimesh.transformations.rotation_matrix(a, (0, 0, 1)) for a in np.radians([0.0, 30.0, 95.0])]
    covered = footprint(view, np.concatenate([np.asarray(points) @ P[:3, :3].T + P[:3, 3] for P in turns]), spacing)
    pixels, rays = pixel_window(view, T[:3, 3], 0.07)
    hit = np.isfinite(DepthRenderer(part.vertices, part.faces).depth(np.array(turns), rays)).any(axis=0)
    assert hit.sum() > 500 and covered[pixels[hit]].all()
    assert covered.sum() < 0.2 * covered.size  # and it is a footprint, not the image


def test_a_sweep_thins_the_window_and_none_keeps_it_whole():
    part = trimesh.creation.box(extents=(0.12, 0.04, 0.02)).apply_translation((0, 0, 0.01))
    scene = workpiece_scene(np.random.default_rng(1), {"part": part}, ["part"])
    view, centre = SceneView(scene.cloud), scene.instances[0].T_camera_model[:3, 3]
    every, _ = pixel_window(view, centre, 0.07)
    assert np.array_equal(pixel_window(view, centre, 0.07, 0.0)[0], every)
    thinned, _ = pixel_window(view, centre, 0.07, sweep=0.05)  # a sweep of 5 cm: many pixels across
    assert set(thinned) < set(every) and len(thinned) < len(every) / 4
