"""A hand-tuned detour controller for snakesim/SnakePegs-v0: it steers the wave first to a waypoint
beside the peg band (2.5 m to the side of the band's middle), then to the goal. It shows that the
goal is reachable around the field (this folder's README). Usage, from the repository root:
.venv/bin/python experiments/pegs-detour/detour_pegs.py [EPISODES] [SEED] [JOINTS] [SIDE] (SIDE: the
waypoint's distance beside the band, 2.5 m by default)."""

from __future__ import annotations

import math
import sys

import gymnasium
import numpy as np
import snakesim  # noqa: F401  (registers the envs)
from snakesim.envs.config import observation_slice


def bearing(obs: np.ndarray, structure: dict[str, int], target: tuple[float, float]) -> float:
    """Bearing of ``target`` from the head, radians (0 ahead, positive to the left), for an
    observation of ``structure`` (the env's ``observation_structure``)."""
    x, y = obs[observation_slice(structure, "base_position")].tolist()
    s, c = obs[observation_slice(structure, "heading")].tolist()
    vx, vy = target[0] - x, target[1] - y
    # The head frame: the goal vector's convention (ahead = -y, left = +x) at heading yaw.
    hx = c * vx + s * vy
    hy = -s * vx + c * vy
    return math.atan2(hx, -hy)


def main() -> None:
    episodes = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    joints = int(sys.argv[3]) if len(sys.argv) > 3 else 10
    side = float(sys.argv[4]) if len(sys.argv) > 4 else 2.5
    env = gymnasium.make("snakesim/SnakePegs-v0", joints=joints)
    structure = env.unwrapped.observation_structure
    wins = 0
    for k in range(episodes):
        obs, info = env.reset(seed=seed + k)
        (sx, sy), (gx, gy) = info["start"][:2], info["goal"]
        d = math.hypot(gx - sx, gy - sy)
        ux, uy = (gx - sx) / d, (gy - sy) / d
        waypoints = [(sx + 0.5 * d * ux - side * uy, sy + 0.5 * d * uy + side * ux), (gx, gy)]
        done = False
        while not done:
            target = waypoints[0]
            x, y = obs[observation_slice(structure, "base_position")].tolist()
            if len(waypoints) > 1 and math.hypot(target[0] - x, target[1] - y) < 1.0:
                waypoints.pop(0)
                target = waypoints[0]
            steer = float(np.clip(-bearing(obs, structure, target), -1.0, 1.0))
            obs, _, terminated, truncated, info = env.step(np.array([steer, 0.0, 0.0], np.float32))
            done = terminated or truncated
        wins += bool(terminated)
    print(f"detour: {wins}/{episodes} episodes reached the goal (seeds {seed}-{seed + episodes - 1})")


if __name__ == "__main__":
    main()
