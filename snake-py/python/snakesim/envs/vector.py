"""Gymnasium's vector API over the batched Rust env: M worlds stepped by one call across threads."""

from __future__ import annotations

import operator
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from snakesim import _core
from snakesim.envs.config import (
    ENV_DEFAULTS,
    GOAL_ENV_DEFAULTS,
    PEGS_ENV_DEFAULTS,
    ROUGH_ENV_DEFAULTS,
    SWIM_ENV_DEFAULTS,
    action_array,
    env_config,
)
from snakesim.envs.env import ClosedCore


class SnakeVectorEnv(VectorEnv):
    """``num_envs`` independent :class:`snakesim.SnakeEnv` worlds as one ``gymnasium.vector.VectorEnv``.

    Worlds step in parallel on Rust threads (no subprocesses, no pickling). Finished episodes reset in
    the same step (``autoreset_mode`` SAME_STEP): the returned observation is the new episode's first,
    and ``infos["final_obs"]`` / ``infos["final_info"]`` (masked by ``infos["_final_obs"]``) hold the
    finished episode's last observation and info. ``reset(seed=s)`` seeds env i with ``s + i``;
    ``reset(seed=[s0, s1, ...])``, one seed per env as Gymnasium's vector envs take them, env i with
    ``s_i`` (None: env i goes on with its own stream, or at the first reset draws a fresh seed; a list
    of another length is a ``ValueError``). ``close()`` releases the worlds; ``reset`` and ``step``
    then raise ``gymnasium.error.ClosedEnvironmentError``. With ``randomize``, ``infos["physics"]``
    (masked by ``infos["_physics"]``) holds what each episode that began drew: every env's at
    ``reset``, the reset ones' in ``step``. Unlike ``SyncVectorEnv``, which batches every env's
    ``info`` at every step, ``step``'s infos hold only these keys, for the envs whose episode ended
    (a step in which none ended gives ``{}``); a running episode's per-step ``info`` comes from
    :class:`snakesim.SnakeEnv` (``gymnasium.make``, or ``gymnasium.make_vec(...,
    vectorization_mode="sync")``).

    Keyword arguments are those of :class:`snakesim.SnakeEnv` (without ``render_mode``).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 16, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be an int >= 1, got {num_envs!r}")
        self._kwargs = dict(kwargs)
        self._core = _core.VecEnv(env_config(**kwargs), num_envs)
        self.num_envs = num_envs
        actions, dim = self._core.action_dim, self._core.observation_dim
        self.single_action_space = spaces.Box(-1.0, 1.0, (actions,), dtype=np.float32)
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (dim,), dtype=np.float32)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        #: A single env's observation parts, name -> size, in order (``SnakeEnv.observation_structure``).
        self.observation_structure: dict[str, int] = self._core.observation_structure

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: Mapping[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if options:
            raise ValueError("SnakeVectorEnv.reset takes no options; use SnakeEnv to place a single snake")
        first = not hasattr(self, "_seeded")
        if seed is None or _is_int(seed):
            seed = None if seed is None else _checked_seed(seed, "seed")
            obs = self._core.reset(_fresh_seed() if seed is None and first else seed)
        else:
            # One seed per env (Gymnasium's list); at the first reset, None draws a fresh seed.
            seeds = _seed_list(seed, self.num_envs)
            obs = self._core.reset_each([_fresh_seed() if s is None and first else s for s in seeds])
        self._seeded = True
        infos: dict[str, Any] = {}
        for index, physics in enumerate(self._core.physics() or ()):
            infos = self._add_info(infos, {"physics": physics}, index)
        return obs, infos

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        obs, rewards, terminated, truncated, finals = self._core.step(action_array(actions))
        infos: dict[str, Any] = {}
        physics = self._core.physics() if finals else None
        for index, final_obs, final_info in finals:
            infos = self._add_info(infos, {"final_obs": final_obs, "final_info": final_info}, index)
            if physics is not None:
                # The physics of the episode that began in this step (same-step autoreset).
                infos = self._add_info(infos, {"physics": physics[index]}, index)
        return obs, rewards, terminated, truncated, infos

    def close_extras(self, **kwargs: Any) -> None:
        # The worlds go with the core; every later use says the env was closed.
        self._core = ClosedCore("this SnakeVectorEnv")


def _fresh_seed() -> int:
    """A seed from the OS's entropy, for a first reset without one (episodes stay random)."""
    return int(np.random.SeedSequence().generate_state(1, dtype=np.uint64)[0] >> 1)


def _is_int(value: Any) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _seed_list(seed: Any, num_envs: int) -> list[int | None]:
    """``reset``'s list of seeds, one per env (None or an int in [0, 2**64)), checked."""
    if not isinstance(seed, (list, tuple, np.ndarray)):
        raise TypeError(
            f"seed must be None, an int or a list of {num_envs} seeds (one per env), "
            f"got {type(seed).__name__}"
        )
    if len(seed) != num_envs:
        raise ValueError(f"seed: a list of seeds holds one per env, {num_envs}, got {len(seed)}")
    return [None if value is None else _checked_seed(value, f"seed[{i}]") for i, value in enumerate(seed)]


def _checked_seed(value: Any, name: str) -> int:
    if not (_is_int(value) and 0 <= operator.index(value) < 2**64):
        shown = repr(value)
        shown = shown if len(shown) <= 24 else shown[:21] + "..."
        raise ValueError(f"{name} must be None or an int in [0, 2**64), got {shown}")
    return operator.index(value)


def _vector_env(
    task: str, defaults: Mapping[str, Any], num_envs: int, kwargs: dict[str, Any]
) -> SnakeVectorEnv:
    """The native vector env of ``task`` for ``gymnasium.make_vec``, with ``gymnasium.make``'s keywords.
    An episode ends where ``gymnasium.make``'s ``TimeLimit`` would end it: at ``max_episode_steps`` if
    given (``None``, the registration's own keyword, means the task's default)."""
    if kwargs.get("task", task) != task:
        raise ValueError(f"this id's task is {task!r}, not {kwargs['task']!r}")
    if kwargs.get("max_episode_steps") is None:
        kwargs["max_episode_steps"] = defaults["max_episode_steps"]
    return SnakeVectorEnv(num_envs, **{**kwargs, "task": task})


# The registered ids' vector entry points (module-level functions, so that a spec pickles):
# ``gymnasium.make_vec("snakesim/SnakeGoal-v0", 8)`` calls goal_vector_env(num_envs=8, ...).
def paper_vector_env(num_envs: int = 16, **kwargs: Any) -> SnakeVectorEnv:
    return _vector_env("paper", ENV_DEFAULTS, num_envs, kwargs)


def goal_vector_env(num_envs: int = 16, **kwargs: Any) -> SnakeVectorEnv:
    return _vector_env("goal", GOAL_ENV_DEFAULTS, num_envs, kwargs)


def pegs_vector_env(num_envs: int = 16, **kwargs: Any) -> SnakeVectorEnv:
    return _vector_env("pegs", PEGS_ENV_DEFAULTS, num_envs, kwargs)


def rough_vector_env(num_envs: int = 16, **kwargs: Any) -> SnakeVectorEnv:
    return _vector_env("rough", ROUGH_ENV_DEFAULTS, num_envs, kwargs)


def swim_vector_env(num_envs: int = 16, **kwargs: Any) -> SnakeVectorEnv:
    return _vector_env("swim", SWIM_ENV_DEFAULTS, num_envs, kwargs)
