"""A gymnasium env for task-level planners: pick which recognised part next, or wait and look again.

The robot does the rest itself (grasp planning, IK, the protective stop); :class:`PickPlaceEnv`
drives a :class:`sim.episode.Episode` one decision at a time. After every executed action the
robot looks at the cell again (``Episode.look``), so the observation always describes the latest
look, and a pick always grasps from the pose that look returned (``Episode.estimate``).

Action ``Discrete(n + 1)`` for a task of n parts (each instance of a part counts: a mesh part with
``count: 2`` is two, in the order ``World.workpieces`` lists them): ``i < n`` picks the i-th, ``n`` waits
``WAIT_S`` and looks again. A pick is refused, without moving anything or advancing the
simulation (the observation stays the same look), when the part was picked already, when the
latest look found someone reaching in, or when that look returned no pose of the part that
``Episode.estimate`` accepts. ``info["action_mask"]`` (int8, (n + 1,)) marks the actions that
would not be refused.

Observation (a dict; part i is the task's i-th part; world frame, metres):

- ``poses`` (n, 7) float32: position and quaternion (w, x, y, z; w >= 0) of the pose a pick
  would use, re-expressed by the part's symmetry that stands on its resting face (the one the
  grasp is planned on); zeros when not seen.
- ``scores`` (n,) float32 in [0, 1]: that estimate's score, 0 when not seen.
- ``seen`` (n,) int8: the latest look returned a pickable pose; ``done`` (n,) int8: picked already.
- ``occupied`` (1,) int8: the latest look found someone reaching over the table.
- ``depth`` (H, W) float32: the latest look's Kinect depth (m, 0 = no return). Oracle looks take
  no picture (the simulator's truth replaces recognition), so their depth is all zeros: rendering
  one would cost ~1 s per reset and ~0.3 s per step on this CPU for a picture nothing uses.

Reward: +1 for a grasp held through the transport, +1 for a part placed (seated in its fixture, or at
rest in the tote), -0.01
per wait, -0.1 per refused pick. ``terminated`` once every part has had its pick; ``truncated``
after ``max_steps`` actions, once the simulated time passes ``MAX_EPISODE_S``, or when the workspace
stays blocked (``info["gave_up"]`` says which); the parts left are then given up in the episode. Made
with ``gymnasium.make``, the step limit is gymnasium's TimeLimit instead, which the env does not see
(gymnasium hides it from the env's spec): its truncation sets no ``info["gave_up"]``, the parts left
stay in ``episode.remaining`` (``episode.result()`` reports them as not reached), and a step after it
would still pick. Call ``reset()`` after any truncation, as gymnasium requires.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from psorr.sensing.kinect_noise import KINECT_V1
from sim.devices.look_picture import LookPicture
from sim.episode import MAX_EPISODE_S, MIN_SCORE, Episode
from sim.errors import ResetNeededError, SimInputError, WorkspaceBlockedError
from sim.modes import PoseSource, parse_mode
from sim.skills.grasp_planning import upright_equivalent
from sim.skills.judging import REST_TOL, PickResult
from sim.skills.perception import Estimate, Look
from sim.world import World, WorldConfig, build_world
from sim.world.parts import instance_names

DEFAULT_TASK = WorldConfig()  # the demo cell: tasks/demo.yaml spells out these defaults
GRASP_REWARD, PLACE_REWARD, WAIT_REWARD, REFUSED_REWARD = 1.0, 1.0, -0.01, -0.1
DEFAULT_MAX_STEPS = 100  # actions in an episode: a few dozen suffice for four parts with the person about
EDGE_MARGIN = 0.1  # m: a symmetric part's upright pose may stand past the table edge by up to its height


class PickPlaceEnv(gym.Env):
    """Pick-and-place in the simulated cell, one planner decision per step (see the module docstring).

    Args:
        task: a task file (``tasks/*.yaml``; a relative path is taken from the working directory) or a
            :class:`sim.world.WorldConfig`; by default the demo cell, as ``tasks/demo.yaml`` gives it.
        poses: a :class:`~sim.modes.PoseSource` or its string, ``"recognized"`` (PSORR on the Kinect's
            cloud) or ``"oracle"`` (the simulator's true poses).
        occluder: a person reaches over the table now and then; overrides the config's ``occluder``.
        render_mode: None or ``"rgb_array"``.
        max_steps: actions (refused ones included) after which the episode is truncated and the parts
            left are given up; None for no limit of the env's own. ``gymnasium.make`` passes None and
            applies the registered ``max_episode_steps`` (DEFAULT_MAX_STEPS) with gymnasium's TimeLimit
            instead, so ``gymnasium.make(..., max_episode_steps=N)`` sets the limit as for any env.

    Attributes:
        parts: the task's parts, in action order. world, episode: the current episode's cell and
            :class:`Episode` (``episode.result()`` summarises it), None before :meth:`reset`.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1}  # a frame per step; a wait step lasts 1 s

    def __init__(self, task: str | os.PathLike | WorldConfig = DEFAULT_TASK,
                 poses: PoseSource | str = PoseSource.RECOGNIZED, occluder: bool = True,
                 render_mode: str | None = None, max_steps: int | None = DEFAULT_MAX_STEPS):
        poses = parse_mode(PoseSource, poses, "poses")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise SimInputError(f"render_mode must be None or one of {self.metadata['render_modes']}, "
                                    f"got {render_mode!r}")
        if max_steps is not None and (isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1):
            raise SimInputError(f"max_steps must be a positive int or None, got {max_steps!r}")
        self.config = replace(_world_config(task), occluder=bool(occluder))
        self.poses, self.occluder, self.render_mode, self.max_steps = poses, bool(occluder), render_mode, max_steps
        self.parts = tuple(instance_names(self.config))
        n, cfg = len(self.parts), self.config
        hx, hy = (v / 2 + EDGE_MARGIN for v in cfg.table_size)
        low = np.tile(np.array([-hx, -hy, 0.0, -1, -1, -1, -1], np.float32), (n, 1))
        high = np.tile(np.array([hx, hy, cfg.table_height + REST_TOL, 1, 1, 1, 1], np.float32), (n, 1))
        self.action_space = spaces.Discrete(n + 1)
        self.observation_space = spaces.Dict({
            "poses": spaces.Box(low, high, dtype=np.float32),
            "scores": spaces.Box(0.0, 1.0, (n,), np.float32),
            "seen": spaces.MultiBinary(n),
            "done": spaces.MultiBinary(n),
            "occupied": spaces.MultiBinary(1),
            "depth": spaces.Box(0.0, KINECT_V1.depth_range[1], cfg.intrinsics.shape, np.float32),
        })
        self.world: World | None = None
        self.episode: Episode | None = None
        self._picture = LookPicture()
        self._look: Look | None = None
        self._estimates: dict[str, Estimate | None] = {}
        self._done: set[str] = set()
        self._steps = self._looks = 0

    # -------------------------------------------------------------------------------- gymnasium API

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Build a new cell and episode from ``self.np_random`` (the only randomness) and take the first look."""
        super().reset(seed=seed)
        self._free()
        self.world = build_world(self.config, self.np_random)
        self.episode = Episode(self.world, self.np_random, self.poses, self.occluder,
                               rgb=self.render_mode == "rgb_array")
        self._done, self._steps, self._looks = set(), 0, 0
        self._take_look()
        return self._observation(), self._info()

    def step(self, action):
        """Pick part ``action`` (or wait when ``action == n``), then look again; see the module docstring."""
        if self.episode is None:
            raise ResetNeededError("call reset() before step()")
        if not self.action_space.contains(action):
            raise SimInputError(f"action must be an int in [0, {len(self.parts)}]: a part's index in "
                                    f"{list(self.parts)}, or {len(self.parts)} to wait; got {action!r}")
        action, episode = int(action), self.episode
        self._steps += 1
        pick, refused, gave_up, reward = None, "", "", 0.0
        try:
            if action == len(self.parts):
                reward = WAIT_REWARD
                episode.wait()
                self._take_look()
            elif refused := self._refusal(self.parts[action]):
                reward = REFUSED_REWARD
            else:
                part = self.parts[action]
                chosen = self._estimates[part]
                pick = episode.pick(part, chosen.T_world_part, looks=self._looks, alternatives=chosen.alternatives)
                self._done.add(part)
                self._looks = 0
                reward = GRASP_REWARD * pick.grasped + PLACE_REWARD * pick.placed
                self._take_look()
        except WorkspaceBlockedError as exc:  # the person kept reaching in: the episode gives up, as run() does
            gave_up = str(exc)
        terminated = not episode.remaining
        out_of_steps = self.max_steps is not None and self._steps >= self.max_steps
        why = gave_up or (f"not picked within {self.max_steps} steps" if out_of_steps else "") or (
            f"not picked within {MAX_EPISODE_S:.0f} s" if self.world.data.time > MAX_EPISODE_S else "")
        truncated = bool(why) and not terminated
        if truncated:
            episode.give_up(why)
        info = self._info(pick=pick, refused=refused, gave_up=why if truncated else "")
        return self._observation(), float(reward), terminated, truncated, info

    def render(self):
        """The Kinect RGB (H, W, 3) uint8 of the latest look; for an oracle look (no picture), the cell now."""
        if self.render_mode is None:
            gym.logger.warn("render() was called without a render_mode: make the env with render_mode='rgb_array'")
            return None
        if self._look is None:
            raise ResetNeededError("call reset() before render()")
        return self._picture.render(self._look, self.world)

    def close(self) -> None:
        """Free the episode's renderers (safe to call twice)."""
        self._free()

    # -------------------------------------------------------------------------------- internals

    def _free(self) -> None:
        if self.episode is not None:
            self.episode.close()
        self._picture.close()
        self.episode = self._look = None

    def _take_look(self) -> None:
        look = self.episode.look()
        self._looks += 1
        # Only a part still waiting has a pose to pick from: a placed one, in its fixture, is no longer pickable.
        self._look = look
        assigned = self.episode.estimates(look)
        self._estimates = {part: assigned.get(part) for part in self.parts}

    def _refusal(self, part: str) -> str:
        """Why a pick of ``part`` now would be refused ("" if it would not)."""
        if part in self._done:
            return f"{part} was picked already"
        if part not in self.episode.remaining:
            return f"{part} was given up: the episode is over, call reset()"
        if self._look.occupied:
            return "someone is reaching over the table: wait and look again"
        if self._estimates[part] is None:
            return (f"the latest look returned no pose of {part} scoring at least {MIN_SCORE} and resting on the "
                    "table: wait and look again")
        return ""

    def _observation(self) -> dict[str, np.ndarray]:
        n, look = len(self.parts), self._look
        poses, scores, seen = np.zeros((n, 7), np.float32), np.zeros(n, np.float32), np.zeros(n, np.int8)
        for i, part in enumerate(self.parts):
            if self._estimates[part] is not None:
                seen[i] = 1
                T, scores[i] = self._estimates[part].T_world_part, self._estimates[part].score
                T = upright_equivalent(np.asarray(T, float), self.world.catalog[part])
                q = np.zeros(4)
                mujoco.mju_mat2Quat(q, np.ascontiguousarray(T[:3, :3]).ravel())
                poses[i] = [*T[:3, 3], *(q if q[0] >= 0 else -q)]
        depth = (look.frame.depth.astype(np.float32) if look.frame is not None
                 else np.zeros(self.config.intrinsics.shape, np.float32))
        return {
            "poses": poses,
            "scores": scores,
            "seen": seen,
            "done": np.array([p in self._done for p in self.parts], np.int8),
            "occupied": np.array([look.occupied], np.int8),
            "depth": depth,
        }

    def _info(self, pick: PickResult | None = None, refused: str = "", gave_up: str = "") -> dict:
        """``pick``: this step's :class:`PickResult` (None if it picked nothing); ``refused``, ``gave_up``: why;
        the episode's ``looks`` and ``occupied_looks``; the latest look's ``intruding`` points and
        ``detections``; ``sim_time`` (s); ``action_mask`` (n + 1,) int8."""
        look, episode = self._look, self.episode
        mask = [not self._refusal(p) for p in self.parts] + [True]
        return {"pick": pick, "refused": refused, "gave_up": gave_up, "looks": episode.looks,
                "occupied_looks": episode.occupied_looks, "intruding": look.intruding,
                "detections": len(look.detections), "sim_time": float(self.world.data.time),
                "action_mask": np.array(mask, np.int8)}


def _world_config(task) -> WorldConfig:
    if isinstance(task, WorldConfig):
        return task
    if isinstance(task, (str, os.PathLike)):
        from sim.world.tasks import load_task

        return load_task(Path(task)).world
    raise SimInputError("task must be a task file path (e.g. 'tasks/demo.yaml') or a sim.world.WorldConfig, "
                            f"got {type(task).__name__}")
