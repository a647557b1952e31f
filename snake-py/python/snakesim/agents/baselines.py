"""Hand-made controllers of the goal task (``snakesim/SnakeGoal-v0``, gait actions): the yardstick a
trained agent must beat. ``snakesim evaluate baseline:steer --joints 10`` evaluates one like an agent.

- ``gait``: the wave at the middle of its amplitude and frequency ranges (0.4 rad, 0.7 Hz), never
  steered: the paper's "sine wave" start, which goes wherever its drift takes it.
- ``steer``: the same wave steered towards the goal, steering action ``clip(-bearing, -1, 1)`` with
  the goal's bearing in radians (0 ahead, positive to the left); the gain was chosen among 0.5, 1, 2
  and 4 (x 0.5 rad) on 10 episodes per snake length, seeds 100-109. On the terrain observation
  the bearing is in its rolled head frame, mirrored while the body is upside down, so steer then
  turns the right way (docs/tasks.md, "The head frame on hills").
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from snakesim import _core
from snakesim.envs.config import observation_slice

#: The controllers by name (snake-core's ``HandController::ALL``).
NAMES = tuple(_core.hand_controller_names())


def goal_bearing(obs: np.ndarray, structure: Mapping[str, int]) -> np.ndarray:
    """The goal's bearing from the head, radians (0 ahead, positive to the left), per row of
    ``obs``, from its ``goal_vector`` (the extended and terrain layouts; ``structure`` is the env's
    ``observation_structure``): for experiments with variants of steer (other gains, targets)."""
    goal = observation_slice(structure, "goal_vector")
    gx, gy = obs[:, goal.start], obs[:, goal.start + 1]
    # The head frame's -y points ahead and its +x to the left.
    return np.arctan2(gx, -gy)


class Controller:
    """``act(obs_batch) -> actions`` of the named baseline in the env of ``env_kwargs`` (SnakeEnv's
    keywords): snake-core's ``HandController``, the one implementation, which also drives
    ``steer_assist`` (:class:`snakesim.wrappers.SteerAssist`). Actions are float64, the values
    the env is given."""

    def __init__(self, name: str, env_kwargs: Mapping[str, Any]) -> None:
        from snakesim.envs.config import env_config

        if name not in NAMES:
            raise ValueError(f"unknown baseline {name!r} (expected one of: {', '.join(NAMES)})")
        self.name, self._config = name, env_config(**env_kwargs)
        # Checks the env once (gait actions, the goal vector), with the core's message.
        dim = _core.Env(self._config).observation_dim
        _core.hand_actions(name, self._config, np.zeros((0, dim), np.float32))

    def act(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        obs = np.ascontiguousarray(np.atleast_2d(np.asarray(obs, dtype=np.float32)))
        return _core.hand_actions(self.name, self._config, obs)


__all__ = ["NAMES", "Controller", "goal_bearing"]
