"""Steer in the extended layout's head frame (the head's x axis) against the terrain layout's rolled
head frame, on the same episodes, with the share of each episode the head spent upside down
(docs/tasks.md, "The head frame on hills"; this folder's README).
Usage, from the repository root: .venv/bin/python experiments/rolled-head-frame/rolled_frame.py
[EPISODES] [SEED] [GROUND]; GROUND is ``rough`` (SnakeRough-v0's defaults) or a world file such as
``worlds/slope-10.yaml`` (relative to the working directory; the goal task on it, with the rough
task's goals, 5-8 m at any bearing, and its 30 s episodes)."""

from __future__ import annotations

import sys

import numpy as np
from snakesim.agents.baselines import Controller
from snakesim.envs.config import ROUGH_ENV_DEFAULTS
from snakesim.envs.env import make_env

JOINTS = 10


def env_kwargs(ground: str, observation: str) -> dict:
    if ground == "rough":
        return {"task": "rough", "joints": JOINTS, "observation": observation}
    return {
        "task": "goal",
        "joints": JOINTS,
        "world": ground,
        "goal_distribution": ROUGH_ENV_DEFAULTS["goal_distribution"],
        "max_episode_steps": ROUGH_ENV_DEFAULTS["max_episode_steps"],
        "observation": observation,
    }


def episode(env, steer: Controller, seed: int) -> tuple[bool, float, float]:
    """Success, the share of env steps with the head upside down, and the final distance (m)."""
    obs, info = env.reset(seed=seed)
    upside_down, steps = 0, 0
    while True:
        obs, _, terminated, truncated, info = env.step(steer.act(obs)[0])
        x, y = env.cube_poses()[0][3:5]
        upside_down += int(1.0 - 2.0 * (x * x + y * y) < 0.0)  # the head's z axis below the horizontal
        steps += 1
        if terminated or truncated:
            return bool(info["success"]), upside_down / steps, float(info["distance"])


def main() -> None:
    episodes = int(sys.argv[1]) if len(sys.argv) > 1 else 30
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 1000
    ground = sys.argv[3] if len(sys.argv) > 3 else "worlds/slope-10.yaml"
    for observation, frame in (("extended", "head's x axis"), ("terrain", "rolled frame")):
        kwargs = env_kwargs(ground, observation)
        env, steer = make_env(**kwargs), Controller("steer", kwargs)
        done = [episode(env, steer, seed + i) for i in range(episodes)]
        lost = [d for d in done if not d[0]]
        rate = np.mean([d[0] for d in done])
        print(f"steer, {frame}: {rate:.2f} of {episodes} episodes (reset seeds {seed}-{seed + episodes - 1})")
        if lost:
            shares = [d[1] for d in lost]
            print(
                f"  {len(lost)} lost: upside down {min(shares):.0%}-{max(shares):.0%} of the episode, "
                f"ending {min(d[2] for d in lost):.1f}-{max(d[2] for d in lost):.1f} m from the goal"
            )


if __name__ == "__main__":
    main()
