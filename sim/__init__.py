"""The simulated robot cell (MuJoCo). ``gymnasium.make("psorr/PickPlace-v0")`` gives :class:`sim.env.PickPlaceEnv`,
``gymnasium.make("psorr/PickPlace-v1", plan=...)`` the plan-level :class:`sim.plans.env.PlanPickPlaceEnv`.

The packages follow what drives what, bottom up:

- :mod:`sim.devices`: the simulated Kinect and the headless OpenGL it renders with;
- :mod:`sim.people`: the person who reaches over the table;
- :mod:`sim.world`: what a cell is built from (config, task files, the arm's MJCF), where the parts go,
  and the assembled, settled cell;
- :mod:`sim.control`: the arm's IK and the stepping of its moves;
- :mod:`sim.skills`: looking and recognising, the catalog's grasps and their planning, pick and place,
  the look in the hand, and judging a pick on the simulator's truth;
- :mod:`sim.recording`: the MP4 and contact sheet of an episode.

On top: :mod:`sim.episode` (looking, deciding and picking until done), :mod:`sim.env` (the same,
one planner decision per step), :mod:`sim.cli` (``psorr-sim``); :mod:`sim.errors` and :mod:`sim.modes`
are the errors and the string modes every layer shares.
"""

import gymnasium

ENV_ID = "psorr/PickPlace-v0"
PLAN_ENV_ID = "psorr/PickPlace-v1"

# Registering an id twice warns (a reload, or a second import under another name): register once.
if ENV_ID not in gymnasium.envs.registry:
    # The step limit is gymnasium's TimeLimit (visible in the spec, set by make's max_episode_steps), not the env's own.
    # 100 is sim.env.DEFAULT_MAX_STEPS, written out so that `import sim` does not load MuJoCo (a test holds them equal).
    gymnasium.register(id=ENV_ID, entry_point="sim.env:PickPlaceEnv", max_episode_steps=100,
                       kwargs={"max_steps": None})
if PLAN_ENV_ID not in gymnasium.envs.registry:
    # 60 is sim.plans.env.DEFAULT_MAX_STEPS, written out for the same reason.
    gymnasium.register(id=PLAN_ENV_ID, entry_point="sim.plans.env:PlanPickPlaceEnv", max_episode_steps=60,
                       kwargs={"max_steps": None})
