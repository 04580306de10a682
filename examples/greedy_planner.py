"""A greedy planner for psorr/PickPlace-v1: move the first detection that a goal object still wants, to the
goal's place; otherwise wait and look again. Prints the success rate over seeded episodes.

    python examples/greedy_planner.py tasks/plans/red_hub.yaml --episodes 5 --poses oracle
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

import sim  # noqa: F401  (registers the envs)
from sim.plans.env import COLOURS


def choose(env, obs, info) -> np.ndarray:
    """The first (slot, destination) that a goal object still wants and the action mask allows; else wait."""
    models, destinations = env.unwrapped.models, env.unwrapped.destinations
    for slot in np.flatnonzero(obs["valid"]):
        model, colour = models[obs["model"][slot]], COLOURS[obs["colour"][slot]]
        for part, wanted_colour, place in info["goal_left"]:
            d = destinations.index(place)
            if part == model and wanted_colour in (None, colour) and info["action_mask"][slot, d]:
                return np.array([slot, d])
    return np.array([env.unwrapped.max_objects, 0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("plan", nargs="?", default="tasks/plans/red_hub.yaml")
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--poses", default="recognized", choices=("recognized", "oracle"))
    args = parser.parse_args()
    env = gymnasium.make("psorr/PickPlace-v1", plan=args.plan, poses=args.poses)
    successes = 0
    for seed in range(args.episodes):
        obs, info = env.reset(seed=seed)
        done = False
        while not done:
            obs, reward, terminated, truncated, info = env.step(choose(env, obs, info))
            done = terminated or truncated
        successes += info["is_success"]
        print(f"episode {seed}: {'goal reached' if info['is_success'] else 'goal not reached'}", flush=True)
    env.close()
    print(f"greedy planner: success rate {successes / args.episodes:.0%} over {args.episodes} episodes")


if __name__ == "__main__":
    main()
