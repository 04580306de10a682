"""``psorr/PickPlace-v1``: a gymnasium env for planners of process plans. Which recognised object to move,
and where; the robot does the rest (grasp planning, IK, the protective stop).

Action Space:
    ``MultiDiscrete([max_objects + 1, len(destinations)])``: a slot of the latest look's detections (the
    last index waits ``WAIT_S`` and looks again), and a destination of :attr:`destinations`: ``"fixture"``
    (the part's own), ``"tote"``, then the fixtures the plan names. A move is refused, without moving
    anything, when the slot is empty, someone is reaching in, the cell does not put that part there, or
    the named fixture is another part's or already filled (a part whose fixtures the plan names goes to
    one of those names, not to ``"fixture"``). ``info["action_mask"]`` ((max_objects + 1,
    len(destinations)) int8) marks the moves that would not be refused.

Observation Space:
    A ``Dict`` (world frame, metres): per detection slot, padded to ``max_objects``, ``model``
    (index into :attr:`models`), ``pose`` (position and quaternion w, x, y, z; w >= 0), ``score``,
    ``colour`` (index into ``psorr.segment.PALETTE``'s names; the last index is "not named") and
    ``valid``; ``occupancy`` (len(destinations),): the share of the fixtures filled, of the tote's slots,
    then 1 for each named fixture filled;
    ``holding`` (1,): the gripper holds a part; ``occupied`` (1,): someone is reaching in; ``depth``: the
    latest look's Kinect depth (zeros for an oracle look).

Rewards:
    +1 for a part placed where the goal wants it (an instance of a goal object's part, in its colour
    when the goal names one, not yet counted, at the destination the goal names); -1 for a part dropped
    or placed where the goal does not want it; -0.01 a wait; -0.1 a refused move.

Rendering:
    ``render_mode="rgb_array"``: the latest look's Kinect RGB (H, W, 3) uint8; ``"depth_array"``: its depth
    (H, W) float32 in metres, 0 where the sensor measured nothing. For an oracle look, which takes no
    picture, the cell as the camera sees it now (its depth without noise).

Episode End:
    Terminated when the goal holds (simulator truth: ``info["is_success"]``; ``info["goal_left"]`` lists the
    goal objects not placed yet, as (part, colour or None, destination)); truncated after
    ``max_steps`` actions, after ``MAX_EPISODE_S`` of simulated time, or when the workspace stays blocked.

Version History:
    v1: the plan-level env (objects by detection, destinations); the fixtures a plan names are
    destinations of their own; ``depth_array`` rendering. v0 (:mod:`sim.env`) picks by part index.
"""

from __future__ import annotations

import dataclasses
import os

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from psorr.segment.colour import PALETTE
from psorr.sensing.kinect_noise import KINECT_V1
from sim.devices.look_picture import LookPicture
from sim.episode import MAX_EPISODE_S, Episode
from sim.errors import ResetNeededError, SimInputError, WorkspaceBlockedError
from sim.modes import PoseSource, parse_mode
from sim.parts.source import PLACES
from sim.plans.plan_file import ProcessPlan, load_plan, named_place_problem
from sim.plans.planning import goal_places
from sim.world import World, build_world

DESTINATIONS = PLACES  # a detection goes to its part's fixture or to the tote, or to a fixture the plan names
COLOURS = (*PALETTE, None)
PLACE_REWARD, WRONG_REWARD, WAIT_REWARD, REFUSED_REWARD = 1.0, -1.0, -0.01, -0.1
DEFAULT_MAX_STEPS = 60


class PlanPickPlaceEnv(gym.Env):
    """A process plan's cell, one move per step (see the module docstring).

    Args:
        plan: a plan file (``tasks/plans/*.yaml``) or a :class:`ProcessPlan`.
        poses: ``"recognized"`` (PSORR on the Kinect's cloud) or ``"oracle"``.
        occluder: a person reaches over the table now and then.
        render_mode: None, ``"rgb_array"`` or ``"depth_array"``.
        max_objects: detection slots; default: the task's part instances.
        max_steps: moves after which the episode is truncated; None for no limit of the env's own.

    Attributes:
        models: the part names a slot's ``model`` indexes. destinations: the names an action's second index
            takes: ``DESTINATIONS``, then the plan's named fixtures. world, episode: the current cell and
            :class:`Episode`, None before :meth:`reset`.
    """

    metadata = {"render_modes": ["rgb_array", "depth_array"], "render_fps": 1}

    def __init__(self, plan: str | os.PathLike | ProcessPlan, poses: PoseSource | str = PoseSource.RECOGNIZED,
                 occluder: bool = True, render_mode: str | None = None, max_objects: int | None = None,
                 max_steps: int | None = DEFAULT_MAX_STEPS):
        self.plan = plan if isinstance(plan, ProcessPlan) else load_plan(plan)
        self.poses, self.occluder = parse_mode(PoseSource, poses, "poses"), bool(occluder)
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise SimInputError(f"render_mode must be None or one of {self.metadata['render_modes']}")
        self.render_mode, self.max_steps = render_mode, max_steps
        self.goal = goal_places(self.plan)  # name -> (object, place); refuses a goal the cell cannot reach
        self.config = dataclasses.replace(self.plan.task.world, occluder=self.occluder, pick=())
        from sim.world.parts import instance_names

        self.models = tuple(sorted(set(self.config.workpieces)))
        n = max_objects or len(instance_names(self.config))
        self.max_objects = n
        self.destinations = (*DESTINATIONS, *(d.name for d in self.plan.destinations))
        self.action_space = spaces.MultiDiscrete([n + 1, len(self.destinations)])
        hx, hy = (v / 2 + 0.1 for v in self.config.table_size)
        low, high = np.array([-hx, -hy, 0, -1, -1, -1, -1], np.float32), np.array([hx, hy, 2, 1, 1, 1, 1], np.float32)
        self.observation_space = spaces.Dict({
            "model": spaces.MultiDiscrete([len(self.models)] * n), "pose": spaces.Box(np.tile(low, (n, 1)),
                                                                                     np.tile(high, (n, 1))),
            "score": spaces.Box(0.0, 1.0, (n,), np.float32), "colour": spaces.MultiDiscrete([len(COLOURS)] * n),
            "valid": spaces.MultiBinary(n),
            "occupancy": spaces.Box(0.0, 1.0, (len(self.destinations),), np.float32),
            "holding": spaces.MultiBinary(1), "occupied": spaces.MultiBinary(1),
            "depth": spaces.Box(0.0, KINECT_V1.depth_range[1], self.config.intrinsics.shape, np.float32),
        })
        self.world: World | None = None
        self.episode: Episode | None = None
        self._slots: list[tuple[str, object]] = []
        self._look = None
        self._counted: set[str] = set()
        self._filled: dict[str, str] = {}  # named fixture -> the body placed in it
        self._steps = 0
        self._picture = LookPicture()

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.close()
        self.world = build_world(self.config, self.np_random)
        colours = any(obj.colour for obj, _ in self.goal.values())
        self.episode = Episode(self.world, self.np_random, self.poses, self.occluder, colours=colours)
        self._counted, self._filled, self._steps = set(), {}, 0
        self._take_look()
        return self._observation(), self._info()

    def step(self, action):
        if self.episode is None:
            raise ResetNeededError("call reset() before step()")
        if not self.action_space.contains(np.asarray(action)):
            raise SimInputError(f"action must be [slot in 0..{self.max_objects}, destination in "
                                f"0..{len(self.destinations) - 1}] ({', '.join(self.destinations)}); got {action!r}")
        slot, where = int(action[0]), self.destinations[int(action[1])]
        self._steps += 1
        reward, refused, pick, gave_up = 0.0, "", None, ""
        try:
            if slot == self.max_objects:
                reward = WAIT_REWARD
                self.episode.wait()
                self._take_look()
            elif refused := self._refusal(slot, where):
                reward = REFUSED_REWARD
            else:
                body, estimate = self._slots[slot]
                pick = self.episode.pick(body, estimate.T_world_part, alternatives=estimate.alternatives)
                reward = self._reward(pick, where)
                self._take_look()
        except WorkspaceBlockedError as exc:
            gave_up = str(exc)
        success = self._goal_holds()
        out = (self.max_steps is not None and self._steps >= self.max_steps) or self.world.data.time > MAX_EPISODE_S
        truncated = not success and (out or bool(gave_up) or not self.episode.remaining)
        return self._observation(), float(reward), success, truncated, self._info(pick, refused, gave_up)

    def render(self):
        """The latest look's Kinect RGB (H, W, 3) uint8, or with ``render_mode="depth_array"`` its depth (H, W)
        float32 (m); for a look without a picture, the cell now."""
        if self.render_mode is None:
            gym.logger.warn("render() was called without a render_mode: make the env with render_mode='rgb_array'")
            return None
        if self._look is None:
            raise ResetNeededError("call reset() before render()")
        if self.render_mode == "depth_array":
            return self._picture.depth(self._look, self.world)
        return self._picture.render(self._look, self.world)

    def close(self) -> None:
        if self.episode is not None:
            self.episode.close()
        self._picture.close()
        self.episode = self._look = None

    # -------------------------------------------------------------------------------- internals

    def _take_look(self) -> None:
        self._look = self.episode.look()
        bound = self.episode.estimates(self._look)
        self._slots = sorted(bound.items())[: self.max_objects]

    def _refusal(self, slot: int, where: str) -> str:
        if slot >= len(self._slots):
            return f"slot {slot} holds no detection in the latest look"
        if self._look.occupied:
            return "someone is reaching over the table: wait and look again"
        body = self._slots[slot][0]
        part = self.world.part_types[body]
        if self.world.places.get(body) != self.plan.kind(where):
            return f"the cell puts {part} in {self.world.places.get(body)}, not in {where}"
        problem = named_place_problem(self.plan.destinations, part, where)
        if problem is not None:
            return f"{problem[0]} ({problem[1]})"
        if where in self._filled:
            return f"{where} is occupied: {self._filled[where]} was placed there"
        return ""

    def _reward(self, pick, where: str) -> float:
        if not pick.placed:
            return WRONG_REWARD
        if self.plan.destination(where) is not None:
            self._filled[where] = pick.part
        name = self._goal_object_for(pick.part, where)
        if name is None:
            return WRONG_REWARD
        self._counted.add(name)
        return PLACE_REWARD

    def _goal_object_for(self, body: str, where: str) -> str | None:
        """The goal object not yet counted that ``body`` (truth: its part and colour) placed at ``where``
        satisfies, if any."""
        kind, colour = self.world.part_types[body], self.world.colour_name(body)
        for name, (obj, place) in self.goal.items():
            if name not in self._counted and obj.part == kind and obj.colour in (None, colour) and place == where:
                return name
        return None

    def _goal_holds(self) -> bool:
        return len(self._counted) == len(self.goal)

    def _observation(self) -> dict:
        n = self.max_objects
        obs = {"model": np.zeros(n, np.int64), "pose": np.zeros((n, 7), np.float32),
               "score": np.zeros(n, np.float32), "colour": np.full(n, len(COLOURS) - 1, np.int64),
               "valid": np.zeros(n, np.int8)}
        for i, (body, estimate) in enumerate(self._slots):
            T, q = estimate.T_world_part, np.zeros(4)
            mujoco.mju_mat2Quat(q, np.ascontiguousarray(T[:3, :3]).ravel())
            obs["model"][i] = self.models.index(self.world.part_types[body])
            obs["pose"][i] = [*T[:3, 3], *(q if q[0] >= 0 else -q)]
            obs["score"][i] = estimate.score
            obs["colour"][i] = COLOURS.index(estimate.colour) if estimate.colour in PALETTE else len(COLOURS) - 1
            obs["valid"][i] = 1
        obs["occupancy"] = self._occupancy()
        obs["holding"] = np.array([self.episode.cell.holding is not None], np.int8)
        obs["occupied"] = np.array([self._look.occupied], np.int8)
        frame = self._look.frame
        obs["depth"] = (frame.depth.astype(np.float32) if frame is not None
                        else np.zeros(self.config.intrinsics.shape, np.float32))
        return obs

    def _occupancy(self) -> np.ndarray:
        places = self.world.places
        placed = {p.part for p in self.episode.picks if p.placed}
        out = []
        for where in DESTINATIONS:
            bodies = [b for b in places if places[b] == where]
            out.append(sum(b in placed for b in bodies) / len(bodies) if bodies else 0.0)
        out += [float(d.name in self._filled) for d in self.plan.destinations]
        return np.array(out, np.float32)

    def _info(self, pick=None, refused: str = "", gave_up: str = "") -> dict:
        mask = np.zeros((self.max_objects + 1, len(self.destinations)), np.int8)
        mask[-1] = 1
        for slot in range(self.max_objects):
            for d, where in enumerate(self.destinations):
                mask[slot, d] = not self._refusal(slot, where)
        left = [(obj.part, obj.colour, place) for name, (obj, place) in self.goal.items() if name not in self._counted]
        return {"is_success": self._goal_holds(), "action_mask": mask, "goal_left": left, "pick": pick,
                "refused": refused, "gave_up": gave_up, "sim_time": float(self.world.data.time)}
