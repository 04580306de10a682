"""What a gymnasium env of the cell shows in ``render()``: the latest look's Kinect RGB, or for a look that
took no picture (an oracle's), the cell as the Kinect sees it now."""

from __future__ import annotations

import mujoco
import numpy as np

from sim.devices.render_backend import ensure_headless_gl


class LookPicture:
    """Renders (H, W, 3) uint8 pictures of the cell from its camera; the renderer is made on first need.
    Call :meth:`close` to free it."""

    def __init__(self):
        self._renderer: mujoco.Renderer | None = None

    def render(self, look, world) -> np.ndarray:
        if look.frame is not None and look.frame.rgb is not None:
            return look.frame.rgb.copy()
        if self._renderer is None:
            ensure_headless_gl()
            self._renderer = mujoco.Renderer(world.model, *world.config.intrinsics.shape)
        self._renderer.update_scene(world.data, camera=world.camera_name)
        return self._renderer.render().copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        self._renderer = None
