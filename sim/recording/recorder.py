"""Recording an episode: an MP4 of the cell as it runs and a PNG contact sheet of its looks and grasps.

:class:`EpisodeRecorder` is the :class:`sim.control.cell.Recorder` that ``psorr-sim run --record DIR`` hands
to each episode. Every ``1 / fps`` s of simulated time it renders two panels side by side, the
Kinect's view and a 3/4 overview of the cell, with a caption of the sim time and what the robot
last did. Each look that got past the person (the robot saw the table, recognised or was told
the poses) becomes a row of the sheet: the Kinect's RGB, the depth cloud (shaded by height above
the table) with the models drawn at the poses the look returned (the oracle's on the RGB), and a
close-up of the gripper if a grasp followed that look.

Rendering is the cost: both panels use one MuJoCo renderer of its own, without shadows or
multisampling (on a CPU-only GL each costs several times the frame), on a copy of the model so the
episode's own renderers keep theirs. ffmpeg encodes in its own process, alongside the physics.
About 15 ms per frame here, plus ffmpeg's 6 ms of CPU: ~0.2 s of wall time per simulated second.
"""

from __future__ import annotations

import copy
import math
from collections import deque
from pathlib import Path

import imageio
import mujoco
import numpy as np
from PIL import Image, ImageDraw, ImageFont

from sim.control.ik import T_world_site
from sim.control.recorder_hooks import Recorder
from sim.devices.render_backend import ensure_headless_gl
from sim.errors import RecordingError, SimInputError
from sim.recording.sheet import ModelOverlay, SheetRow, height_shade, project_points, write_sheet
from sim.world import World

PANEL_W, PANEL_H = 480, 360  # px of each video panel (the Kinect's 4:3)
CAPTION_H = 24  # px of the caption strip under the panels (keeps the frame height a multiple of 16)
SHEET_ROWS = 8  # the sheet shows the last this many looks
MODEL_POINTS = 1500  # model surface points drawn per detection on the sheet
BANNER_S = 1.5  # s of simulated time a look's or grasp's caption stays on the video
# The overview looks from the arm's side (-x, -y) across the table, so the person at +x faces the camera.
OVERVIEW_AZIMUTH, OVERVIEW_ELEVATION = 60.0, -25.0  # deg
OVERVIEW_DISTANCE, OVERVIEW_ABOVE_TABLE = 1.5, 0.2  # m from the look-at point; m of it above the table centre
CLOSE_UP_ELEVATION, CLOSE_UP_DISTANCE = -15.0, 0.3  # deg; m from the tool site


class EpisodeRecorder(Recorder):
    """Writes ``directory/<name>.mp4`` and ``directory/<name>_sheet.png`` for one episode.

    Args:
        directory: where the files go; created if missing.
        name: file stem, e.g. ``"episode_0_1"``.
        fps: video frames per second of simulated time.

    Attributes:
        looks, occupied_looks, grasps: counted so far (occupied looks found the person reaching in).

    Raises:
        RecordingError: ``directory`` cannot be created (e.g. it is an existing file).
        SimInputError: fps is not positive.

    Use for one episode (one world), then call :meth:`close` to get the files.
    """

    def __init__(self, directory: Path, name: str, fps: float = 10.0):
        if fps <= 0:
            raise SimInputError(f"fps must be > 0, got {fps}; the default is 10")
        directory = Path(directory)
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except (FileExistsError, NotADirectoryError):
            raise RecordingError(f"cannot record into {directory}: it or one of its parents is a file; pass a "
                                 "directory path to --record (it is created if missing)") from None
        except OSError as exc:
            raise RecordingError(f"cannot create {directory} ({exc.strerror}): pass a writable directory "
                                 "to --record") from None
        self.fps, self.name = float(fps), name
        self.video_path = directory / f"{name}.mp4"
        self.sheet_path = directory / f"{name}_sheet.png"
        self._next_frame_s = 0.0
        self._caption, self._caption_until_s = "", -math.inf  # what the robot last did, shown until then (sim s)
        self.looks = self.occupied_looks = self.grasps = 0
        self._rows_made = 0  # looks that got past the person, plus grasps no such look led to
        self._rows: deque[SheetRow] = deque(maxlen=SHEET_ROWS)
        self._renderer: mujoco.Renderer | None = None
        self._writer = None
        self._model_points: dict[str, np.ndarray] = {}
        self._written: list[Path] | None = None
        self._font = ImageFont.load_default(size=14)

    # -------------------------------------------------------------------------------- Recorder protocol

    def tick(self, world: World, data: mujoco.MjData) -> None:
        """After each physics step: a video frame when ``data.time`` reaches the next frame time."""
        if data.time + 1e-9 < self._next_frame_s:
            return
        self._next_frame_s = (math.floor(data.time * self.fps + 1e-6) + 1) / self.fps
        kinect = self._render(world, data, world.camera_name)
        overview = self._render(world, data, _free_camera((0.0, 0.0, world.table_top + OVERVIEW_ABOVE_TABLE),
                                                          OVERVIEW_AZIMUTH, OVERVIEW_ELEVATION, OVERVIEW_DISTANCE))
        caption = f"t = {data.time:5.1f} s"
        if data.time <= self._caption_until_s:
            caption += f"   {self._caption}"
        frame = np.concatenate([np.concatenate([kinect, overview], axis=1), self._caption_strip(caption)], axis=0)
        if self._writer is None:
            # The frame is 960x384, a multiple of 16 (no resizing); "veryfast" halves x264's CPU at the same size.
            self._writer = imageio.get_writer(self.video_path, fps=self.fps, codec="libx264", quality=6,
                                              macro_block_size=16, pixelformat="yuv420p",
                                              output_params=["-preset", "veryfast"])
        self._writer.append_data(frame)

    def looked(self, world: World, data: mujoco.MjData, look, library) -> None:
        """After each look: caption it, and keep a sheet row unless the person was in the way."""
        self.looks += 1
        n = self.looks
        if look.occupied:
            self.occupied_looks += 1
            self._show(data, f"look {n}: person in view, waiting")
            return
        if look.frame is not None:
            rgb, depth_shade = look.frame.rgb, height_shade(look.frame, world.table_top)
            models = [(d.model, d.score, self._points(world, library, d.model), np.asarray(d.T_cloud_model))
                      for d in look.detections]
        else:  # the oracle: no frame, the true poses; draw them on the camera's RGB
            rgb, depth_shade = self._render(world, data, world.camera_name), None
            T_camera_world = np.linalg.inv(world.T_world_camera)
            models = [(part, e.score, self._points(world, None, part), T_camera_world @ e.T_world_part)
                      for part, ests in look.estimates.items() for e in ests]
        scale = rgb.shape[1] / world.config.intrinsics.width
        overlays = tuple(ModelOverlay(name, float(score), project_points(pts, T, world, scale))
                         for name, score, pts, T in models)
        self._rows.append(SheetRow(n, float(data.time), rgb, depth_shade, overlays))
        self._rows_made += 1
        found = ", ".join(f"{o.name} {o.score:.2f}" for o in overlays) or "nothing recognised"
        self._show(data, f"look {n}: {found}")

    def grasped(self, world: World, data: mujoco.MjData, part: str) -> None:
        """When the gripper has closed on ``part``: a close-up for the row of the look that led to it."""
        self.grasps += 1
        close_up = self._render(world, data, _close_up_camera(world, data))
        if not self._rows or self._rows[-1].grasp is not None:  # a grasp no look of ours led to
            self._rows.append(SheetRow(0, float(data.time), np.zeros_like(close_up), None, ()))
            self._rows_made += 1
        self._rows[-1].grasp, self._rows[-1].grasp_part = close_up, part
        self._show(data, f"grasped {part}")

    # -------------------------------------------------------------------------------- output

    @property
    def rows(self) -> tuple[SheetRow, ...]:
        """The sheet's rows so far (the last SHEET_ROWS), oldest first."""
        return tuple(self._rows)

    def close(self) -> list[Path]:
        """Finish the MP4, write the sheet, free the renderer; return the files written (MP4 only if ticked)."""
        if self._written is not None:
            return list(self._written)
        written = []
        if self._writer is not None:
            self._writer.close()
            written.append(self.video_path)
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        waited = f", {self.occupied_looks} found the person reaching in (not shown)" if self.occupied_looks else ""
        capped = f"; the last {len(self._rows)} of {self._rows_made} rows" if self._rows_made > len(self._rows) else ""
        write_sheet(self.sheet_path, list(self._rows), f"{self.name}: {self.looks} looks{waited}, "
                     f"{self.grasps} grasps{capped}")
        self._written = written + [self.sheet_path]
        return list(self._written)

    # -------------------------------------------------------------------------------- helpers

    def _show(self, data: mujoco.MjData, text: str) -> None:
        self._caption, self._caption_until_s = text, data.time + BANNER_S

    def _render(self, world: World, data: mujoco.MjData, camera) -> np.ndarray:
        """(PANEL_H, PANEL_W, 3) uint8 view of ``data`` from a named camera or an ``MjvCamera``."""
        if self._renderer is None:
            ensure_headless_gl()
            model = copy.copy(world.model)  # a copy: these are read when the GL context is made
            model.vis.quality.offsamples = 0
            # Coarser capsules and cylinders (the person, the table legs) look the same at this size, ~30% faster.
            model.vis.quality.numslices, model.vis.quality.numstacks = 12, 6
            self._renderer = mujoco.Renderer(model, PANEL_H, PANEL_W)
            self._renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
        self._renderer.update_scene(data, camera=camera)
        return self._renderer.render().copy()

    def _caption_strip(self, text: str) -> np.ndarray:
        strip = Image.new("RGB", (2 * PANEL_W, CAPTION_H), (20, 20, 20))
        ImageDraw.Draw(strip).text((8, 4), text, fill=(235, 235, 235), font=self._font)
        return np.asarray(strip)

    def _points(self, world: World, library, part: str) -> np.ndarray:
        """(<= MODEL_POINTS, 3) surface points of the part ``part`` (not a body) in its model frame (metres)."""
        if part not in self._model_points:
            if library is not None:
                pts = library.model(part).points
            else:
                import trimesh

                info = world.catalog[world.bodies_of(part)[0]]
                pts = trimesh.sample.sample_surface(info.load_mesh(), MODEL_POINTS, seed=0)[0]
            self._model_points[part] = np.asarray(pts)[:: max(1, len(pts) // MODEL_POINTS)]
        return self._model_points[part]


def _free_camera(lookat, azimuth: float, elevation: float, distance: float) -> mujoco.MjvCamera:
    """A free camera at ``distance`` (m) from ``lookat`` (3,), from ``azimuth`` and ``elevation`` (deg)."""
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.lookat[:] = lookat
    camera.azimuth, camera.elevation, camera.distance = azimuth, elevation, distance
    return camera


def _close_up_camera(world: World, data: mujoco.MjData) -> mujoco.MjvCamera:
    """Looks at the tool site along the tool's y, so the pads (closing along x) are seen side by side."""
    T = T_world_site(world.model, data, world.arm.tool_site)
    azimuth = math.degrees(math.atan2(T[1, 1], T[0, 1]))
    return _free_camera(T[:3, 3], azimuth, CLOSE_UP_ELEVATION, CLOSE_UP_DISTANCE)

