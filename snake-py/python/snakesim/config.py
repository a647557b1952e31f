"""Keyword arguments of the envs, checked in Python and handed to Rust as JSON."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

PRESETS = ("paper", "snakebot-gym")
OBSERVATIONS = ("paper", "extended")


def _pair(name: str, value: Any) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be two numbers (x, y), got {value!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return x, y


def env_config(
    joints: int = 5,
    preset: str = "paper",
    goal: Sequence[float] = (0.0, -10.0),
    goal_radius: float = 1.0,
    max_episode_steps: int = 5000,
    physics_steps_per_env_step: int = 1,
    start: Mapping[str, Any] | None = None,
    action_scale: float = 1.0,
    observation: str = "paper",
    reward: Mapping[str, Any] | None = None,
    snake: Mapping[str, Any] | None = None,
) -> str:
    """The JSON configuration of one env; raises ValueError/TypeError naming a bad argument.

    ``start`` may set ``x``, ``y`` and ``yaw`` as [low, high] ranges and ``z``; ``reward`` the optional
    reward terms; ``snake`` any physical parameter of the preset (e.g. ``{"link_mass": 0.5}``).
    The Rust side rejects unknown keys with a message naming them.
    """
    if isinstance(joints, bool) or not isinstance(joints, int):
        raise TypeError(f"joints must be an int, got {type(joints).__name__}")
    if joints < 1:
        raise ValueError(f"joints must be at least 1, got {joints}")
    if preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r} (expected one of: {', '.join(PRESETS)})")
    if observation not in OBSERVATIONS:
        raise ValueError(f"unknown observation {observation!r} (expected one of: {', '.join(OBSERVATIONS)})")
    config: dict[str, Any] = {
        "joints": joints,
        "preset": preset,
        "goal": list(_pair("goal", goal)),
        "goal_radius": float(goal_radius),
        "max_episode_steps": int(max_episode_steps),
        "physics_steps_per_env_step": int(physics_steps_per_env_step),
        "action_scale": float(action_scale),
        "observation": observation,
    }
    for name, table in (("start", start), ("reward", reward), ("snake", snake)):
        if table is not None:
            if not isinstance(table, Mapping):
                raise TypeError(f"{name} must be a mapping, got {type(table).__name__}")
            config[name] = dict(table)
    try:
        return json.dumps(config, allow_nan=False)
    except ValueError:
        raise ValueError("env arguments must be finite numbers") from None
