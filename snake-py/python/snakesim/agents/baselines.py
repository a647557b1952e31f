"""Hand-made controllers: the yardstick a trained agent must beat. ``snakesim evaluate baseline:steer
--joints 10`` evaluates one like an agent.

Of the goal task (``snakesim/SnakeGoal-v0``, gait actions):

- ``gait``: the wave at the middle of its amplitude and frequency ranges (0.4 rad, 0.7 Hz), never
  steered: the paper's "sine wave" start, which goes wherever its drift takes it.
- ``steer``: the same wave steered towards the goal, steering action ``clip(-bearing, -1, 1)`` with
  the goal's bearing in radians (0 ahead, positive to the left); the gain was chosen among 0.5, 1, 2
  and 4 (x 0.5 rad) on 10 episodes per snake length, seeds 100-109. On the terrain observation
  the bearing is in its rolled head frame, mirrored while the body is upside down, so steer then
  turns the right way (docs/tasks.md, "The head frame on hills").

Of the paper's env (``snakesim/Snake-v0``, joint targets; ``--env paper``), the controllers a run's
``init`` imitates (snake-core's ``JointsSine``), with a clock per env that restarts with its episode:

- ``sine``: pybullet snake.py's wave as joint targets, never steered.
- ``steered_sine``: the same, its steering offset following the base's x off the goal's (0.15 rad
  per metre, at most 0.3 rad): the paper's observation has the base position and no heading.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from snakesim import _core
from snakesim.envs.config import observation_slice

#: The gait-action controllers by name (snake-core's ``HandController::ALL``).
GAIT_NAMES = tuple(_core.hand_controller_names())
#: The joint-target controllers by name (snake-core's ``Imitable::ALL``, ``init.imitate``'s names).
JOINT_NAMES = tuple(_core.joint_controller_names())
#: Every baseline by name.
NAMES = GAIT_NAMES + JOINT_NAMES


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
    keywords). A gait-action one is snake-core's ``HandController``, the one implementation, which
    also drives ``steer_assist`` (:class:`snakesim.wrappers.SteerAssist`); its actions are float64,
    the values the env is given. A joint-target one (``sine``, ``steered_sine``) is snake-core's
    ``JointsSine``, a wave per row of the batch: ``restart(i)`` when row i's episode ends
    (:func:`snakesim.agents.evaluation.run_episodes` does), ``restart()`` before a new run. ``hold``
    (a gait-action one only): its amplitude and frequency actions, each in [-1, 1], instead of the
    middle of their ranges (0, 0), e.g. a harder-driven wave (``snakesim evaluate --hold``)."""

    def __init__(
        self, name: str, env_kwargs: Mapping[str, Any], hold: tuple[float, float] | None = None
    ) -> None:
        from snakesim.envs.config import env_config

        if name not in NAMES:
            raise ValueError(f"unknown baseline {name!r} (expected one of: {', '.join(NAMES)})")
        if hold is not None and name not in GAIT_NAMES:
            raise ValueError(
                f"hold: {name} sets joint targets: only the gait-action baselines ({', '.join(GAIT_NAMES)}) "
                "hold an amplitude and a frequency"
            )
        self.name, self._config = name, env_config(**env_kwargs)
        self._hold = {} if hold is None else {"amplitude": float(hold[0]), "frequency": float(hold[1])}
        # Checks the env once (gait actions and the goal vector, or joint targets), with the core's
        # message.
        env = _core.Env(self._config)
        self._action_dim = env.action_dim
        self._waves: Any = None
        if name in JOINT_NAMES:
            _core.JointsSine(name, self._config, 1)
        else:
            try:
                _core.hand_actions(
                    name, self._config, np.zeros((0, env.observation_dim), np.float32), **self._hold
                )
            except ValueError as error:
                # The core checks the held actions before the env: name them as the caller's ``hold``.
                held = str(error).startswith(("amplitude:", "frequency:"))
                raise ValueError(f"hold: {error}" if held else str(error)) from None

    def act(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        obs = np.ascontiguousarray(np.atleast_2d(np.asarray(obs, dtype=np.float32)))
        if self.name in GAIT_NAMES:
            return _core.hand_actions(self.name, self._config, obs, **self._hold)
        if len(obs) == 0:
            return np.zeros((0, self._action_dim), np.float32)
        if self._waves is None or self._waves.envs != len(obs):
            self._waves = _core.JointsSine(self.name, self._config, len(obs))
        return self._waves.act(obs)

    def restart(self, env: int | None = None) -> None:
        """Row ``env``'s episode ended (every row's, with None): its wave starts over."""
        if self._waves is None:
            return
        if env is None:
            self._waves = None
        else:
            self._waves.reset(env)


__all__ = ["GAIT_NAMES", "JOINT_NAMES", "NAMES", "Controller", "goal_bearing"]
