"""The paper's snake environment as a Gymnasium env."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from snakesim import _core
from snakesim.config import ENV_DEFAULTS as _D
from snakesim.config import env_config
from snakesim.render import top_down


class SnakeEnv(gymnasium.Env):
    """A snake of N position-controlled joints that must crawl to a goal on a plane.

    The environment of "Simulating Snakes" (snakebot-gym's ``Snake-v0``) on snakesim's Bullet core;
    with ``preset="snakebot-gym"`` and the default arguments it gives bit-identical observations and
    rewards to the paper's pybullet env for the same start and actions.

    **Action space**: ``Box(-1, 1, (N,), float32)``. Joint target angles, radians, times
    ``action_scale``; actions are clipped to [-1, 1] first. NaN, a wrong shape or a non-numeric dtype
    raise ``ValueError``.

    **Observation space**: ``Box(-inf, inf, (2 + 2N,), float32)`` with ``observation="paper"``: base
    (head) x, base y, then for each joint its (angle, velocity) pair, interleaved. With
    ``observation="extended"`` six values follow: the goal vector in the head frame (2), sin and cos of
    the heading (2) and the head's planar velocity in the head frame (2).

    **Reward**: minus the planar head-goal distance; 100 instead once the head is within
    ``goal_radius`` of the goal. Optional terms (``reward={...}``, off by default): progress toward
    the goal, a smoothness penalty on the change of targets between steps, an energy penalty. Every
    term is reported in ``info``.

    **Episode end**: ``terminated`` when the goal is reached; ``truncated`` after
    ``max_episode_steps`` env steps (5000, as ``Snake-v0``).

    **Start state**: each reset builds a fresh world, drops the snake from z = 0.5 at
    x, y ~ U(-0.5, 0.5) with heading ~ U(-0.2, 0.2) rad, and takes one physics step before the first
    observation, as the paper's env does. ``reset(options={"start": (x, y, z, yaw)})`` places it
    exactly; ``options={"goal": (x, y)}`` moves the goal for that episode.

    **Arguments**: ``joints`` (5), ``preset`` ("paper": every cube 0.06 kg; "snakebot-gym": links
    1.0 kg as the paper's code), ``goal`` ((0, -10)), ``goal_radius`` (1.0), ``max_episode_steps``
    (5000), ``physics_steps_per_env_step`` (1), ``start`` (ranges of x, y, yaw and z),
    ``action_scale`` (1.0), ``observation`` ("paper"), ``reward`` (optional terms), ``snake``
    (physical parameters over the preset's), ``render_mode`` (None or "rgb_array").

    **Version history**: v0, the paper's env.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(
        self,
        joints: int = _D["joints"],
        preset: str = _D["preset"],
        goal: Sequence[float] = tuple(_D["goal"]),
        goal_radius: float = _D["goal_radius"],
        max_episode_steps: int = _D["max_episode_steps"],
        physics_steps_per_env_step: int = _D["physics_steps_per_env_step"],
        start: Mapping[str, Any] | None = None,
        action_scale: float = _D["action_scale"],
        observation: str = _D["observation"],
        reward: Mapping[str, Any] | None = None,
        snake: Mapping[str, Any] | None = None,
        render_mode: str | None = None,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"unknown render_mode {render_mode!r} (expected None or 'rgb_array')")
        # Kept as given (the Rust side checks them), for pickling and for SB3's get_attr.
        self._kwargs = dict(
            joints=joints,
            preset=preset,
            goal=goal,
            goal_radius=goal_radius,
            max_episode_steps=max_episode_steps,
            physics_steps_per_env_step=physics_steps_per_env_step,
            start=start,
            action_scale=action_scale,
            observation=observation,
            reward=reward,
            snake=snake,
        )
        self._config_json = env_config(**self._kwargs)
        self._env = _core.Env(self._config_json)
        self.render_mode = render_mode
        self.joints = self._env.joints
        self.action_space = spaces.Box(-1.0, 1.0, (self.joints,), dtype=np.float32)
        self.observation_space = spaces.Box(-np.inf, np.inf, (self._env.observation_dim,), dtype=np.float32)
        self._trail: list[tuple[float, float]] = []

    @property
    def config(self) -> dict[str, Any]:
        """The resolved configuration (every field, defaults included)."""
        return json.loads(self._env.config_json())

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        options = dict(options or {})
        start = options.pop("start", None)
        goal = options.pop("goal", None)
        if options:
            raise ValueError(f"unknown reset options {sorted(options)} (expected 'start' and/or 'goal')")
        if seed is None and not hasattr(self, "_seeded"):
            # Without a seed the first reset draws one from Gymnasium's RNG, so episodes stay random.
            seed = int(self.np_random.integers(2**63 - 1))
        self._seeded = True
        obs, info = self._env.reset(
            seed, None if start is None else tuple(start), None if goal is None else tuple(goal)
        )
        self._trail = []
        return obs, info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self._env.step(np.asarray(action))
        if self.render_mode is not None:
            self._trail.append((float(obs[0]), float(obs[1])))
        return obs, reward, terminated, truncated, info

    def cube_poses(self) -> np.ndarray:
        """The pose of every cube now, shape (N + 1, 7): x, y, z, qx, qy, qz, qw (metres; quaternion
        x, y, z, w), the head (base) first, as a fresh array. Raises RuntimeError before the first reset."""
        return np.asarray(self._env.cube_poses(), dtype=np.float64)

    @property
    def goal(self) -> tuple[float, float]:
        """The current episode's goal (x, y): ``goal``, or the one passed in ``reset(options=...)``."""
        x, y = self._env.goal
        return float(x), float(y)

    @property
    def half_extent(self) -> float:
        """Half the side of each cube, metres."""
        return float(self._env.half_extent)

    def render(self) -> np.ndarray | None:
        """A top-down RGB image (``render_mode="rgb_array"``) of the snake, its path and the goal."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        goal = self._env.goal
        return top_down(
            self._env.cube_poses(),
            self._env.half_extent,
            goal,
            self._env.goal_radius,
            trail=np.asarray(self._trail) if self._trail else None,
        )

    def close(self) -> None:
        pass

    # Pickling keeps the arguments; the unpickled env starts fresh and needs a reset, as after __init__.
    def __getstate__(self) -> dict[str, Any]:
        return {"kwargs": self._kwargs, "render_mode": self.render_mode}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(**state["kwargs"], render_mode=state["render_mode"])
