"""One render for depth and bodies (sim.devices.depth_render) gives what mujoco.Renderer's two passes give."""

import mujoco
import numpy as np
import pytest

from sim.devices.depth_render import DepthBodyRenderer
from sim.world import WorldConfig, build_world


def _two_passes(renderer: mujoco.Renderer, model: mujoco.MjModel):
    """Depth (m, 0 for none or the far plane) and body ids (-1 for none) as mujoco.Renderer gives them."""
    renderer.enable_depth_rendering()
    depth = renderer.render().astype(np.float64)
    renderer.enable_segmentation_rendering()
    seg = renderer.render()
    is_geom = seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM)
    body = np.where(is_geom, model.geom_bodyid[np.where(is_geom, seg[..., 0], 0)], -1).astype(np.int64)
    far = 0.99 * model.vis.map.zfar * model.stat.extent
    return np.where((body >= 0) & (depth < far), depth, 0.0), body


@pytest.fixture(scope="module")
def world():
    return build_world(WorldConfig(workpieces=("u_channel", "chassis")), np.random.default_rng(3))


@pytest.mark.parametrize("size", [(120, 160), (480, 640)])
def test_one_render_gives_the_two_passes_depth_and_bodies_to_the_bit(world, size):
    data = world.reset(mujoco.MjData(world.model))
    data.qpos[world.model.jnt_qposadr[0]] += 0.3  # the arm turned into the view, over the parts
    mujoco.mj_forward(world.model, data)
    camera = world.model.camera(world.camera_name).id
    one = DepthBodyRenderer(world.model, *size, camera)  # first: it sets up headless OpenGL
    two = mujoco.Renderer(world.model, *size)
    try:
        two.update_scene(data, camera=camera)
        depth_two, body_two = _two_passes(two, world.model)
        depth_one, body_one = one.render(data)
    finally:
        two.close()
        one.close()
    assert np.array_equal(body_one, body_two) and np.array_equal(depth_one, depth_two)
    seen = set(np.unique(body_one)) - {-1}
    assert {world.model.body(p).id for p in ("u_channel", "chassis")} <= seen
    assert (depth_one > 0).mean() > 0.5
