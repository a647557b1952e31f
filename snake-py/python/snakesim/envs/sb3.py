"""Stable-Baselines3's ``VecEnv`` over the batched Rust env."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces

from snakesim import _core, extras
from snakesim.envs.config import ENV_DEFAULTS, action_array, env_config
from snakesim.envs.env import ClosedCore

extras.require("sb3", "snakesim.SnakeVecEnv (Stable-Baselines3's VecEnv)")

from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvStepReturn  # noqa: E402


class SnakeVecEnv(VecEnv):
    """``num_envs`` snake worlds stepped together on Rust threads, as SB3's ``VecEnv``.

    A drop-in replacement for ``make_vec_env(SnakeEnv, n_envs)`` with ``DummyVecEnv`` or
    ``SubprocVecEnv``, without subprocesses. Finished episodes reset in the same step, as SB3 expects:
    ``infos[i]["terminal_observation"]`` holds the last observation and
    ``infos[i]["TimeLimit.truncated"]`` says whether the episode was truncated rather than ended. Wrap it
    in ``VecMonitor`` for episode returns in the logs. ``seed(s)`` makes the next reset seed env i
    with ``s + i``. ``close()`` releases the worlds; ``reset`` and ``step`` then raise
    ``gymnasium.error.ClosedEnvironmentError``.

    Keyword arguments are those of :class:`snakesim.SnakeEnv` (without ``render_mode``).
    """

    def __init__(self, num_envs: int = 16, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be an int >= 1, got {num_envs!r}")
        self._kwargs = dict(kwargs)
        self._core = _core.VecEnv(env_config(**kwargs), num_envs)
        actions, dim = self._core.action_dim, self._core.observation_dim
        super().__init__(
            num_envs,
            spaces.Box(-np.inf, np.inf, (dim,), dtype=np.float32),
            spaces.Box(-1.0, 1.0, (actions,), dtype=np.float32),
        )
        #: A single env's observation parts, name -> size, in order (``SnakeEnv.observation_structure``).
        self.observation_structure: dict[str, int] = self._core.observation_structure
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        seeds = [s for s in self._seeds if s is not None]
        seed = seeds[0] if seeds else None
        if seed is None and not hasattr(self, "_seeded"):
            seed = int(np.random.SeedSequence().generate_state(1, dtype=np.uint64)[0] >> 1)
        self._seeded = True
        obs = self._core.reset(seed)
        self._reset_seeds()
        self._reset_options()
        physics = self._core.physics()
        if physics is not None:
            # SB3's reset returns no infos; its VecEnvs keep them in reset_infos.
            self.reset_infos = [{"physics": p} for p in physics]
        return obs

    def seed(self, seed: int | None = None) -> Sequence[None | int]:
        # Env i gets seed + i at the next reset (the Rust side adds i), as SB3's own VecEnvs do.
        if seed is None:
            seed = int(np.random.default_rng().integers(0, 2**32 - 1))
        self._seeds = [seed + i for i in range(self.num_envs)]
        return self._seeds

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        if self._actions is None:
            raise RuntimeError("step_wait() called without step_async()")
        obs, rewards, terminated, truncated, finals = self._core.step(action_array(self._actions))
        self._actions = None
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        physics = self._core.physics() if finals else None
        for index, final_obs, final_info in finals:
            info = dict(final_info)
            info["terminal_observation"] = final_obs
            info["TimeLimit.truncated"] = bool(truncated[index] and not terminated[index])
            if physics is not None:
                # The physics the next episode (reset in this step) drew.
                info["physics"] = physics[index]
            infos[index] = info
        return obs, rewards.astype(np.float32), terminated | truncated, infos

    def close(self) -> None:
        # The worlds go with the core; reset and step then raise ClosedEnvironmentError.
        self._core = ClosedCore("this SnakeVecEnv")

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        if attr_name == "render_mode":
            return [None for _ in self._get_indices(indices)]
        if attr_name in self._kwargs or attr_name in ("joints", "preset"):
            value = self._kwargs.get(attr_name, ENV_DEFAULTS.get(attr_name))
            return [value for _ in self._get_indices(indices)]
        raise AttributeError(f"SnakeVecEnv envs have no attribute {attr_name!r}")

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        raise AttributeError("SnakeVecEnv envs are configured at construction; create a new SnakeVecEnv")

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **kwargs: Any
    ) -> list:
        raise AttributeError(f"SnakeVecEnv envs have no method {method_name!r} callable from Python")

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None for _ in range(self.num_envs)]
