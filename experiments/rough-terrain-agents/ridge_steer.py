"""A hand-made controller for snakesim/SnakeRough-v0 with a ridge across the way (the env of
experiments/rough-terrain-agents/rough-10-ridge.yaml) that sees the ground: ``baseline:steer`` in the
terrain observation's rolled head frame, except that where the height map shows ground ahead (up to
1.5 m) more than RISE above the head it turns, at full steering, towards the lower side (chosen when
it first sees the rise and kept), and once the way ahead is clear goes straight on for HOLD seconds
before it steers at the goal again: a bug algorithm's wall following, as far as a 1.5 m height map
allows. It measures whether seeing the ridge is enough, without learning, to go around it (this
folder's README, "A ridge across the way"). Its memory belongs to an env slot of the batch, not to an
episode: an episode that starts while the slot's previous episode was holding straight holds on for
the rest of HOLD.
Usage, from the repository root: .venv/bin/python experiments/rough-terrain-agents/ridge_steer.py
[EPISODES] [SEED] [RISE] [HOLD] [CONFIG] (CONFIG: a run configuration whose env to run,
rough-10-ridge.yaml beside this script by default; its height map, whatever its size, is the one the
rule reads: ahead is the rows in front of the head's, the sides the columns beside its own)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from snakesim.agents.baselines import goal_bearing
from snakesim.agents.evaluation import run_episodes, summarize
from snakesim.envs.config import observation_slice
from snakesim.envs.env import make_env
from snakesim.runs import config as runconfig

#: The ridge attempt's run configuration, whose env this controller runs in.
CONFIG = Path(__file__).resolve().parent / "rough-10-ridge.yaml"

#: Env steps a second (the goal task's 30 Hz actions).
STEPS_PER_SECOND = 30


def ridge_steer(structure: dict[str, int], rise: float, hold: float):
    """``act(obs_batch)`` for a terrain observation of ``structure`` (the env's
    ``observation_structure``)."""
    height_map = observation_slice(structure, "height_map")
    n = int(round(structure["height_map"] ** 0.5))  # the map is a square grid
    c = n // 2
    side: np.ndarray | None = None  # per env slot: the side it turns to (0: none chosen)
    holding: np.ndarray | None = None  # per env slot: steps left going straight

    def act(obs: np.ndarray) -> np.ndarray:
        nonlocal side, holding
        obs = np.atleast_2d(obs)
        if side is None or len(side) != len(obs):
            side, holding = np.zeros(len(obs)), np.zeros(len(obs), dtype=int)
        # Rows 0..c-1 lie ahead (the head frame's -y), columns above c to the left.
        ahead = obs[:, height_map].reshape(-1, n, n)[:, :c, :]
        left, right = ahead[:, :, c + 1 :].max(axis=(1, 2)), ahead[:, :, :c].max(axis=(1, 2))
        blocked = ahead.max(axis=(1, 2)) > rise
        steering = np.clip(-goal_bearing(obs, structure), -1.0, 1.0)
        for i in range(len(obs)):
            if blocked[i]:
                if side[i] == 0:
                    # Positive steering bends towards the left: turn to the lower side.
                    side[i] = 1.0 if left[i] < right[i] else -1.0
                steering[i], holding[i] = side[i], int(hold * STEPS_PER_SECOND)
            elif holding[i] > 0:
                steering[i], holding[i] = 0.0, holding[i] - 1
                if holding[i] == 0:
                    side[i] = 0.0
        actions = np.zeros((len(obs), 3), dtype=np.float32)
        actions[:, 0] = steering
        return actions

    return act


def main() -> None:
    args = sys.argv[1:]
    episodes = int(args[0]) if len(args) > 0 else 100
    seed = int(args[1]) if len(args) > 1 else 900000
    rise = float(args[2]) if len(args) > 2 else 0.5
    hold = float(args[3]) if len(args) > 3 else 5.0
    run = runconfig.load(Path(args[4]) if len(args) > 4 else CONFIG)
    joints = run["joints"]
    kwargs = {**run["env"], "joints": joints}
    structure = make_env(**kwargs).observation_structure
    summary = summarize(run_episodes(ridge_steer(structure, rise, hold), kwargs, episodes, seed))
    low, high = summary["success_rate_ci95"]
    rate = summary["success_rate"]
    print(f"ridge_steer (rise {rise} m, hold {hold} s): success {rate:.2f} ({low:.2f}-{high:.2f})")


if __name__ == "__main__":
    main()
