"""Pick a headless OpenGL backend for MuJoCo's offscreen renderer: EGL if it works here, else OSMesa.

MuJoCo chooses its GL context class from ``MUJOCO_GL`` when ``mujoco`` is first imported, and
PyOpenGL fixes its platform from ``PYOPENGL_PLATFORM`` when ``OpenGL`` is first imported. Without
``MUJOCO_GL`` MuJoCo takes GLFW, which needs a display. :func:`ensure_headless_gl` fixes both:

- ``MUJOCO_GL`` set by the user: respected as it is (``PYOPENGL_PLATFORM`` is filled in to match).
- unset: ``PYOPENGL_PLATFORM`` if it names egl or osmesa; otherwise EGL is probed once per process
  in a child process (a failed EGL start cannot be undone in-process, because PyOpenGL keeps its
  platform), else OSMesa is used. Both variables are set, and if ``mujoco`` was already imported
  its context class is re-bound to the chosen backend, so calling it any time before the first
  ``mujoco.Renderer`` of the process is enough (``sim.devices.sensor.DepthCamera`` does).

Setting ``MUJOCO_GL=egl`` or ``osmesa`` in the environment skips the probe (about 1 s).
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from enum import StrEnum

from sim.errors import RenderBackendError
from sim.modes import choices


class HeadlessBackend(StrEnum):
    """MuJoCo's headless OpenGL backends, in the order they are tried (the values of ``MUJOCO_GL``)."""

    EGL = "egl"
    OSMESA = "osmesa"


_PROBE = """
import mujoco
from mujoco.egl import GLContext
ctx = GLContext(8, 8)
ctx.make_current()
model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='.1'/></worldbody></mujoco>")
mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
ctx.free()
"""

_chosen: HeadlessBackend | str | None = None


def _egl_works(timeout: float = 60.0) -> bool:
    """True when a child process can create an EGL context and a MuJoCo render context."""
    env = dict(os.environ, MUJOCO_GL="egl", PYOPENGL_PLATFORM="egl")
    try:
        done = subprocess.run(
            [sys.executable, "-c", _PROBE], env=env, capture_output=True, timeout=timeout, check=False
        )
    except (OSError, subprocess.TimeoutExpired):
        return False
    return done.returncode == 0


def ensure_headless_gl() -> HeadlessBackend | str:
    """Make MuJoCo render offscreen without a display; return the backend in use: a :class:`HeadlessBackend`,
    or the user's own ``MUJOCO_GL`` (such as "glfw") as given.

    Idempotent and cheap after the first call. Must run before the first ``mujoco.Renderer`` (or
    ``mujoco.GLContext``) of the process; importing ``mujoco`` before it is fine.

    Raises:
        RenderBackendError: ``OpenGL`` was already imported for another platform, or neither
            backend can be loaded (install libegl1 / libosmesa6, or set MUJOCO_GL).
    """
    global _chosen
    if _chosen is not None:
        return _chosen
    backend = os.environ.get("MUJOCO_GL", "").strip().lower()
    if not backend:
        platform = os.environ.get("PYOPENGL_PLATFORM", "").strip().lower()
        headless = choices(HeadlessBackend)
        backend = platform if platform in headless else HeadlessBackend.EGL if _egl_works() else HeadlessBackend.OSMESA
        os.environ["MUJOCO_GL"] = str(backend)
    if backend in choices(HeadlessBackend):
        backend = HeadlessBackend(backend)
        platform = os.environ.setdefault("PYOPENGL_PLATFORM", backend.value)
        if platform.lower() != backend:
            raise RenderBackendError(
                f"PYOPENGL_PLATFORM={platform!r} does not match MUJOCO_GL={backend.value!r}; unset it or set it to "
                f"one of {choices(HeadlessBackend)} to match"
            )
        opengl = sys.modules.get("OpenGL.platform")
        loaded = getattr(opengl, "PLATFORM", None)
        if loaded is not None and backend not in type(loaded).__module__.lower():
            raise RenderBackendError(
                f"PyOpenGL was already loaded for {type(loaded).__name__}; call ensure_headless_gl() (or set "
                f"MUJOCO_GL to one of {choices(HeadlessBackend)}) before anything imports OpenGL"
            )
        _bind_mujoco_context(backend)
    _chosen = backend
    return backend


def _bind_mujoco_context(backend: HeadlessBackend) -> None:
    """Point an already imported mujoco at the backend's GLContext (mujoco binds it at import time)."""
    gl_context = sys.modules.get("mujoco.rendering.classic.gl_context")
    try:
        context_class = importlib.import_module(f"mujoco.{backend}").GLContext
    except (ImportError, AttributeError, OSError) as exc:
        raise RenderBackendError(
            f"cannot load MuJoCo's {backend} backend ({type(exc).__name__}: {exc}); install libegl1 for egl or "
            f"libosmesa6 for osmesa (make system-libs), or set MUJOCO_GL to one of {choices(HeadlessBackend)}"
        ) from None
    if gl_context is not None:
        gl_context.GLContext = context_class
    mujoco = sys.modules.get("mujoco")
    if mujoco is not None:
        mujoco.GLContext = context_class
