"""A hand-made controller for snakesim/SnakeRough-v0 with a crater in the way (the env of
experiments/rough-terrain-agents/rough-10-crater.yaml) that sees the ground: ``baseline:steer`` in the
terrain observation's rolled head frame, except that where the height map shows a drop ahead (a
crater's wall: a point up to 1.5 m ahead more than DROP below the head) it turns away from the deeper
side until the way ahead is clear. It measures whether seeing the crater is enough, without learning,
to go around it (this folder's README, "A crater in the way").
Usage, from the repository root: .venv/bin/python experiments/rough-terrain-agents/crater_steer.py
[EPISODES] [SEED] [DROP] [CONFIG] (CONFIG: a run configuration whose env to run, rough-10-crater.yaml
beside this script by default)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from snakesim.agents.baselines import goal_bearing
from snakesim.agents.evaluation import run_episodes, summarize
from snakesim.envs.config import observation_slice
from snakesim.envs.env import make_env
from snakesim.runs import config as runconfig

#: The crater attempt's run configuration, whose env this controller runs in.
CONFIG = Path(__file__).resolve().parent / "rough-10-crater.yaml"


def crater_steer(structure: dict[str, int], drop: float):
    """``act(obs_batch)`` for a terrain observation of ``structure`` (the env's
    ``observation_structure``)."""
    height_map = observation_slice(structure, "height_map")
    side = int(round(structure["height_map"] ** 0.5))  # the map is a square grid
    c = side // 2

    def act(obs: np.ndarray) -> np.ndarray:
        obs = np.atleast_2d(obs)
        actions = np.zeros((len(obs), 3), dtype=np.float32)
        actions[:, 0] = np.clip(-goal_bearing(obs, structure), -1.0, 1.0)
        # Rows 0..c-1 lie ahead (the head frame's -y), columns above c to the left.
        ahead = obs[:, height_map].reshape(-1, side, side)[:, :c, :]
        left, right = ahead[:, :, c + 1 :].min(axis=(1, 2)), ahead[:, :, :c].min(axis=(1, 2))
        blocked = ahead.min(axis=(1, 2)) < -drop
        # Positive steering bends towards the left: turn away from the deeper side.
        actions[blocked, 0] = np.where(left[blocked] < right[blocked], 1.0, -1.0)
        return actions

    return act


def main() -> None:
    args = sys.argv[1:]
    episodes = int(args[0]) if len(args) > 0 else 100
    seed = int(args[1]) if len(args) > 1 else 900000
    drop = float(args[2]) if len(args) > 2 else 0.5
    run = runconfig.load(Path(args[3]) if len(args) > 3 else CONFIG)
    joints = run["joints"]
    kwargs = {**run["env"], "joints": joints}
    structure = make_env(**kwargs).observation_structure
    summary = summarize(run_episodes(crater_steer(structure, drop), kwargs, episodes, seed))
    low, high = summary["success_rate_ci95"]
    print(f"crater_steer (drop {drop} m): success {summary['success_rate']:.2f} ({low:.2f}-{high:.2f})")


if __name__ == "__main__":
    main()
