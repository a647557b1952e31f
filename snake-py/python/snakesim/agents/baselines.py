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

from snakesim.envs.config import observation_slice

#: The controllers by name.
NAMES = ("gait", "steer")


def goal_bearing(obs: np.ndarray, structure: Mapping[str, int]) -> np.ndarray:
    """The goal's bearing from the head, radians (0 ahead, positive to the left), per row of ``obs``,
    from its ``goal_vector`` (the extended and terrain layouts; ``structure`` is the env's
    ``observation_structure``)."""
    goal = observation_slice(structure, "goal_vector")
    gx, gy = obs[:, goal.start], obs[:, goal.start + 1]
    # The head frame's -y points ahead and its +x to the left.
    return np.arctan2(gx, -gy)


class Controller:
    """``act(obs_batch) -> actions`` of a named baseline for observations of ``structure`` (the env's
    ``observation_structure``)."""

    def __init__(self, name: str, structure: Mapping[str, int]) -> None:
        if name not in NAMES:
            raise ValueError(f"unknown baseline {name!r} (expected one of: {', '.join(NAMES)})")
        self.name, self.structure = name, dict(structure)

    def act(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        obs = np.atleast_2d(np.asarray(obs, dtype=np.float32))
        actions = np.zeros((obs.shape[0], 3), dtype=np.float32)
        if self.name == "steer":
            actions[:, 0] = np.clip(-goal_bearing(obs, self.structure), -1.0, 1.0)
        return actions


# The action keys that put baseline:steer into an agent's env; a hand-made controller drives
# without them.
_STEER_KEYS = ("steer_residual", "steer_near_goal")


def plain_gait(env_kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """``env_kwargs`` for a hand-made controller: where an agent's steering corrects steer's
    (``action.steer_residual``) or steer takes over near the goal (``action.steer_near_goal``), the
    controller sets the steering itself, so it drives the plain gait in the same episodes (the
    layouts and goals come from the seeds, not the actions)."""
    kwargs = dict(env_kwargs)
    action = kwargs.get("action")
    if isinstance(action, Mapping) and any(action.get(k) for k in _STEER_KEYS):
        kwargs["action"] = {k: v for k, v in action.items() if k not in _STEER_KEYS}
    return kwargs


def check_env(config: dict[str, Any]) -> None:
    """Raises ValueError unless the resolved env ``config`` has what the baselines need."""
    if config["action"]["mode"] != "gait" or config["observation"] not in ("extended", "terrain"):
        raise ValueError(
            "the baselines need action mode 'gait' and observation 'extended' or 'terrain', got "
            f"{config['action']['mode']!r} and {config['observation']!r}"
        )


__all__ = ["NAMES", "Controller", "check_env", "goal_bearing", "plain_gait"]
