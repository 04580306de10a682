"""Depth and the body each pixel sees, from one render: :class:`DepthBodyRenderer`.

``mujoco.Renderer`` gives depth and segmentation in two passes, though both come from the same segmented
render (its depth mode turns segmentation on for accuracy). The cell's safety monitor reads both four times
a simulated second, so this renderer draws the scene once and reads both buffers. The depth and body ids are
those ``mujoco.Renderer``'s two passes give, to the bit (tests/sim/devices/test_depth_render.py).
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim.devices.render_backend import ensure_headless_gl

_MAX_GEOM = 10000


class DepthBodyRenderer:
    """An offscreen ``height`` x ``width`` view of ``model`` through its camera ``camera_id``.

    :meth:`render` returns the (H, W) z-depth in metres (0 where no geom is hit, or only the far plane) and
    the (H, W) int64 id of the body each pixel sees (-1 for none). Call :meth:`close` to free the GL context.
    """

    def __init__(self, model: mujoco.MjModel, height: int, width: int, camera_id: int):
        ensure_headless_gl()
        self.model, self.height, self.width = model, height, width
        self._gl = mujoco.GLContext(width, height)
        self._gl.make_current()
        self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._scene = mujoco.MjvScene(model, maxgeom=_MAX_GEOM)
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
        self._scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        self._option, self._camera = mujoco.MjvOption(), mujoco.MjvCamera()
        self._camera.type, self._camera.fixedcamid = mujoco.mjtCamera.mjCAMERA_FIXED, camera_id
        self._rect = mujoco.MjrRect(0, 0, width, height)

    @property
    def drawn_groups(self) -> np.ndarray:
        """(6,) uint8: which geom groups the render draws (MuJoCo's default: 0, 1 and 2)."""
        return np.array(self._option.geomgroup)

    def render(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """Depth (m) and body ids of ``data``'s state (kinematics must be current)."""
        model = self.model
        mujoco.mjv_updateScene(model, data, self._option, None, self._camera, mujoco.mjtCatBit.mjCAT_ALL,
                               self._scene)
        self._gl.make_current()
        mujoco.mjr_render(self._rect, self._scene, self._context)
        ids = np.empty((self.height, self.width, 3), dtype=np.uint8)
        buffer = np.empty((self.height, self.width), dtype=np.float32)
        mujoco.mjr_readPixels(ids, buffer, self._rect, self._context)
        depth = np.flipud(self._metres(buffer)).astype(np.float64)
        body = np.flipud(self._bodies(ids))
        far = 0.99 * model.vis.map.zfar * model.stat.extent
        return np.where((body >= 0) & (depth < far), depth, 0.0), body

    def _metres(self, buffer: np.ndarray) -> np.ndarray:
        """The depth buffer (reversed z, in [0, 1]) as float32 metres along the optical axis, as
        ``mujoco.Renderer`` computes them (in float32 where OpenGL does)."""
        extent = self.model.stat.extent
        zfar = np.float32(self.model.vis.map.zfar * extent)
        znear = np.float32(self.model.vis.map.znear * extent)
        c = -(zfar + znear) / (zfar - znear)
        d = -(np.float32(2) * zfar * znear) / (zfar - znear)
        c, d = np.float32(-0.5) * c - np.float32(0.5), np.float32(-0.5) * d
        return (d / (buffer.astype(np.float64) + c)).astype(np.float32)

    def _bodies(self, ids: np.ndarray) -> np.ndarray:
        """The segmentation colours (a geom's segid + 1) as body ids; -1 for the background and non-geoms."""
        segid = ids[..., 0].astype(np.int64) + ids[..., 1].astype(np.int64) * 256 + ids[..., 2].astype(np.int64) * 65536
        scene = self._scene
        lookup = np.full(scene.ngeom + 1, -1, dtype=np.int64)
        for g in scene.geoms[:scene.ngeom]:
            if g.segid != -1 and g.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                lookup[g.segid + 1] = self.model.geom_bodyid[g.objid]
        return lookup[segid]

    def close(self) -> None:
        """Free the GL context; the renderer cannot render afterwards."""
        if self._gl is not None:
            self._gl.make_current()
            self._context.free()
            self._gl.free()
            self._gl = None
