"""What a gymnasium env of the cell shows in ``render()``: the latest look's Kinect RGB or depth, or for a
look that took no picture (an oracle's), the cell as the Kinect sees it now."""

from __future__ import annotations

import mujoco
import numpy as np

from sim.devices.render_backend import ensure_headless_gl


class LookPicture:
    """Renders (H, W, 3) uint8 pictures and (H, W) float32 depth images (m) of the cell from its camera; the
    renderer is made on first need. Call :meth:`close` to free it."""

    def __init__(self):
        self._renderer: mujoco.Renderer | None = None

    def render(self, look, world) -> np.ndarray:
        if look.frame is not None and look.frame.rgb is not None:
            return look.frame.rgb.copy()
        return self._cell_now(world, depth=False)

    def depth(self, look, world) -> np.ndarray:
        """The look's Kinect depth (m, 0 where it measured nothing); for a look without a picture, the cell's
        depth now as the camera would measure it without noise."""
        if look.frame is not None:
            return look.frame.depth.astype(np.float32)
        return self._cell_now(world, depth=True).astype(np.float32)

    def _cell_now(self, world, depth: bool) -> np.ndarray:
        if self._renderer is None:
            ensure_headless_gl()
            self._renderer = mujoco.Renderer(world.model, *world.config.intrinsics.shape)
        if depth:
            self._renderer.enable_depth_rendering()
        try:
            self._renderer.update_scene(world.data, camera=world.camera_name)
            return self._renderer.render().copy()
        finally:
            self._renderer.disable_depth_rendering()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        self._renderer = None
