"""Whether the safety monitor's image could show anything above the workspace: :class:`MonitorGate`.

The monitor counts the points of a 160x120 depth render that stand above the workspace's ceiling and are
neither the robot nor the part in its hand (:meth:`sim.skills.perception.Perception.monitor_intruding`). Most
of an episode nobody reaches in, and that render (about 10 ms with software OpenGL, four times a simulated
second) was a third of an episode's wall time. The simulator knows where every geom is, so the render is
skipped while no geom it would draw reaches within the depth noise's reach of the ceiling over the
workspace: then no point it could give stands there.
"""

from __future__ import annotations

import mujoco
import numpy as np

_NOISE_SIGMAS = 6.0  # depth sigmas a measured point may stray; one point in 10^9 strays further


class MonitorGate:
    """Which geoms could put a point above the workspace in the monitor's render.

    Args:
        model: the cell's model.
        drawn_groups: (6,) the geom groups the monitor draws (its ``MjvOption.geomgroup``).
        ignored_bodies: body ids whose pixels the monitor drops (the robot's own arm).
        half_extent: (hx, hy) m, the workspace's footprint about the world origin (the table's).
        ceiling: m, world z above which a point intrudes.
        margin: m, how far a measured point may lie from the surface it measures (the depth noise's reach
            at the workspace's far corner; :func:`noise_margin`).
    """

    def __init__(self, model: mujoco.MjModel, drawn_groups: np.ndarray, ignored_bodies: np.ndarray,
                 half_extent: tuple[float, float], ceiling: float, margin: float):
        drawn = np.asarray(drawn_groups, dtype=bool)[np.clip(model.geom_group, 0, len(drawn_groups) - 1)]
        self._geoms = np.flatnonzero(drawn & ~np.isin(model.geom_bodyid, ignored_bodies))
        self._body = model.geom_bodyid[self._geoms]
        self._local = model.geom_aabb[self._geoms]  # (G, 6): centre and half sizes in each geom's frame
        self._lo = np.array([-half_extent[0] - margin, -half_extent[1] - margin, ceiling - margin])
        self._hi = np.array([half_extent[0] + margin, half_extent[1] + margin, np.inf])
        self._margin = margin

    def may_intrude(self, data: mujoco.MjData, held_body: int | None = None, tool: np.ndarray | None = None,
                    held_radius: float = 0.0) -> bool:
        """False when no drawn geom's world box reaches over the workspace within ``margin`` of the ceiling;
        a geom of ``held_body`` does not count while its box lies within ``held_radius`` m of ``tool`` (3,),
        less the margin, since the monitor drops every point that close to the tool while a part is held."""
        R = data.geom_xmat[self._geoms].reshape(-1, 3, 3)
        centre = data.geom_xpos[self._geoms] + np.einsum("gij,gj->gi", R, self._local[:, :3])
        half = np.einsum("gij,gj->gi", np.abs(R), self._local[:, 3:])
        reaches = np.all((centre + half >= self._lo) & (centre - half <= self._hi), axis=1)
        if held_body is not None and tool is not None:
            farthest = np.linalg.norm(np.abs(centre - tool) + half, axis=1)
            reaches &= ~((self._body == held_body) & (farthest <= held_radius - self._margin))
        return bool(reaches.any())


def noise_margin(depth_sigma, T_world_camera: np.ndarray, half_extent: tuple[float, float], top: float) -> float:
    """m: how far the depth noise may move a point over the workspace, ``_NOISE_SIGMAS`` times its sigma at
    the farthest corner of the table top (``depth_sigma``: metres of depth to metres of sigma)."""
    hx, hy = half_extent
    corners = np.array([[sx * hx, sy * hy, top] for sx in (-1, 1) for sy in (-1, 1)])
    farthest = float(np.linalg.norm(corners - T_world_camera[:3, 3], axis=1).max())
    return _NOISE_SIGMAS * float(np.max(depth_sigma(np.array([farthest]))))
