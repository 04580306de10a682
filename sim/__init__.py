"""The simulated robot cell (MuJoCo). ``gymnasium.make("psorr/PickPlace-v0")`` gives :class:`sim.env.PickPlaceEnv`."""

import gymnasium

ENV_ID = "psorr/PickPlace-v0"

# Registering an id twice warns (a reload, or a second import under another name): register once.
if ENV_ID not in gymnasium.envs.registry:
    # The step limit is gymnasium's TimeLimit (visible in the spec, set by make's max_episode_steps), not the env's own.
    # 100 is sim.env.DEFAULT_MAX_STEPS, written out so that `import sim` does not load MuJoCo (a test holds them equal).
    gymnasium.register(id=ENV_ID, entry_point="sim.env:PickPlaceEnv", max_episode_steps=100,
                       kwargs={"max_steps": None})
