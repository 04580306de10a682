"""A random planner for psorr/PickPlace-v1: a move drawn from those the action mask allows (waiting among
them). Prints the success rate over seeded episodes, the floor a planner should beat.

    python examples/random_planner.py tasks/plans/red_hub.yaml --episodes 5 --poses oracle
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

import sim  # noqa: F401  (registers the envs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("plan", nargs="?", default="tasks/plans/red_hub.yaml")
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--poses", default="recognized", choices=("recognized", "oracle"))
    args = parser.parse_args()
    env = gymnasium.make("psorr/PickPlace-v1", plan=args.plan, poses=args.poses)
    rng, successes = np.random.default_rng(0), 0
    for seed in range(args.episodes):
        obs, info = env.reset(seed=seed)
        done = False
        while not done:
            allowed = np.argwhere(info["action_mask"])
            obs, reward, terminated, truncated, info = env.step(allowed[rng.integers(len(allowed))])
            done = terminated or truncated
        successes += info["is_success"]
        print(f"episode {seed}: {'goal reached' if info['is_success'] else 'goal not reached'}", flush=True)
    env.close()
    print(f"random planner: success rate {successes / args.episodes:.0%} over {args.episodes} episodes")


if __name__ == "__main__":
    main()
