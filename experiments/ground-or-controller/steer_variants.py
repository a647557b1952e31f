"""Is a task's failure the ground's or the controller's? Runs ``baseline:steer`` with fixed gait
settings (amplitude and frequency actions, steering gain) on the same episodes and counts, per
episode, how many of the variants reach the goal (this folder's README).
Usage, from the repository root: .venv/bin/python experiments/ground-or-controller/steer_variants.py
[EPISODES] [SEED] [TASK] [JOINTS] [--nudge] [--rolled]; TASK is goal, pegs
or rough. ``--nudge`` runs steer's own wave with its steering gain changed by 0.1 % steps instead
(NUDGED): a task whose outcomes such a change flips is decided by chaos, not by the ground.
``--rolled`` gives steer the terrain observation, whose goal bearing is in the rolled head frame
(docs/tasks.md, "The head frame on hills"), instead of the extended one."""

from __future__ import annotations

import sys

import numpy as np
from snakesim.agents.baselines import goal_bearing
from snakesim.agents.evaluation import run_episodes
from snakesim.envs.env import make_env
from win_overlap import print_counts  # this directory's script, on sys.path when run as a script

#: (amplitude action, frequency action, steering gain): steer's own (0, 0, 1), and each changed.
VARIANTS = (
    (0.0, 0.0, 1.0),
    (-0.5, 0.0, 1.0),
    (0.5, 0.0, 1.0),
    (0.0, -0.5, 1.0),
    (0.0, 0.5, 1.0),
    (-0.5, 0.5, 1.0),
    (0.5, -0.5, 1.0),
    (0.0, 0.0, 2.0),
    (0.0, 0.0, 0.5),
)

#: Steer's own wave with its gain changed by -0.2 % to +0.2 %.
NUDGED = tuple((0.0, 0.0, gain) for gain in (1.0, 1.001, 0.999, 1.002, 0.998))


def steer(structure: dict[str, int], amplitude: float, frequency: float, gain: float):
    def act(obs: np.ndarray) -> np.ndarray:
        obs = np.atleast_2d(obs)
        actions = np.zeros((obs.shape[0], 3), dtype=np.float32)
        actions[:, 0] = np.clip(-gain * goal_bearing(obs, structure), -1.0, 1.0)
        actions[:, 1:] = amplitude, frequency
        return actions

    return act


def main() -> None:
    flags = {"--nudge", "--rolled"}
    args = [a for a in sys.argv[1:] if a not in flags]
    variants = NUDGED if "--nudge" in sys.argv[1:] else VARIANTS
    observation = "terrain" if "--rolled" in sys.argv[1:] else "extended"
    episodes = int(args[0]) if len(args) > 0 else 50
    seed = int(args[1]) if len(args) > 1 else 1000
    task = args[2] if len(args) > 2 else "rough"
    joints = int(args[3]) if len(args) > 3 else 10
    kwargs = {"task": task, "joints": joints, "observation": observation}
    structure = make_env(**kwargs).observation_structure
    wins = []
    for amplitude, frequency, gain in variants:
        done = run_episodes(
            steer(structure, amplitude, frequency, gain),
            kwargs,
            episodes,
            seed,
        )
        wins.append([bool(e["success"]) for e in done])
        rate = np.mean(wins[-1])
        print(
            f"amplitude {amplitude:+.1f}, frequency {frequency:+.1f}, gain {gain:.3f}: {rate:.2f}", flush=True
        )
    print_counts(np.array(wins))


if __name__ == "__main__":
    main()
