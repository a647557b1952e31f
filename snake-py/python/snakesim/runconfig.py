"""The configuration of a training run: defaults (the paper's Table 1), YAML files, command-line overrides.

A run is described by a :class:`TrainConfig`. Its sources, lowest precedence first: the defaults below,
a YAML file (``--config``), then explicit command-line flags (and ``--set key=value``). The resolved
configuration is written to ``config.yaml`` in the run directory and reads back equal.

YAML layout (every key optional; unknown keys are errors)::

    joints: 5              # N revolute joints (N + 1 cubes)
    arch: small            # small: pi/vf [64, 64]; large: shared [128, 128] then pi/vf [64, 64]
    preset: snakebot-gym   # paper (all cubes 0.06 kg) or snakebot-gym (links 1.0 kg, the paper's code)
    timesteps: 20000000
    n_envs: 16
    seed: 42
    eval_freq: 250000      # in total timesteps; 0: evaluate only at the end
    eval_episodes: 10
    eval_seed: null        # null: seed + 1000
    checkpoint_freq: 1000000   # in total timesteps; 0: no periodic checkpoints
    normalize: false       # wrap the training env in VecNormalize (the paper does not)
    device: auto           # auto, cpu, cuda or cuda:N
    torch_threads: null    # null: torch's default
    ppo: {learning_rate: 3.0e-4, n_steps: 4096, batch_size: 64, n_epochs: 10, gamma: 0.99,
          gae_lambda: 0.95, clip_range: 0.2, ent_coef: 0.0, vf_coef: 0.5, max_grad_norm: 0.5}
    env: {}                # more SnakeEnv keywords: goal, goal_radius, max_episode_steps, observation, ...
"""

from __future__ import annotations

import copy
import inspect
import math
import os
from collections.abc import Mapping
from typing import Any

import yaml

from snakesim.config import PRESETS, env_config

ARCHS = ("small", "large")
EVAL_SEED_OFFSET = 1000

# The paper's Table 1 (SB3's PPO defaults with n_steps 4096 and 10 epochs), and SB3's other defaults.
PPO_DEFAULTS: dict[str, Any] = {
    "learning_rate": 3e-4,
    "n_steps": 4096,
    "batch_size": 64,
    "n_epochs": 10,
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "ent_coef": 0.0,
    "vf_coef": 0.5,
    "max_grad_norm": 0.5,
}

DEFAULTS: dict[str, Any] = {
    "joints": 5,
    "arch": "small",
    "preset": "paper",
    "timesteps": 20_000_000,
    "n_envs": 16,
    "seed": 42,
    "eval_freq": 250_000,
    "eval_episodes": 10,
    "eval_seed": None,
    "checkpoint_freq": 1_000_000,
    "normalize": False,
    "device": "auto",
    "torch_threads": None,
    "ppo": PPO_DEFAULTS,
    "env": {},
}

# Keys that define what is learnt; --resume refuses to change them.
IDENTITY_KEYS = ("joints", "arch", "preset", "n_envs", "seed", "eval_seed", "normalize", "ppo", "env")

# SnakeEnv keywords that the `env` table may set (joints and preset are top-level keys).
ENV_KEYS = tuple(p for p in inspect.signature(env_config).parameters if p not in ("joints", "preset"))


class ConfigError(ValueError):
    """A configuration that cannot be used; the message names the key and what is wrong."""


def _int(name: str, value: Any, minimum: int | None = None, optional: bool = False) -> int | None:
    if value is None and optional:
        return None
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"{name} must be an integer, got {value!r}")
    if minimum is not None and value < minimum:
        raise ConfigError(f"{name} must be at least {minimum}, got {value}")
    return value


def _float(name: str, value: Any, low: float | None = None, high: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ConfigError(f"{name} must be finite, got {value}")
    if (low is not None and value < low) or (high is not None and value > high):
        raise ConfigError(f"{name} must be in [{low}, {high}], got {value}")
    return value


def _choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise ConfigError(f"unknown {name} {value!r} (expected one of: {', '.join(choices)})")
    return value


def _unknown(table: str, keys: Any, allowed: Any) -> None:
    unknown = sorted(set(keys) - set(allowed))
    if unknown:
        where = f" in {table}" if table else ""
        raise ConfigError(
            f"unknown key{'s' if len(unknown) > 1 else ''}{where}: {', '.join(map(str, unknown))} "
            f"(expected: {', '.join(allowed)})"
        )


def _device(value: Any) -> str:
    if not isinstance(value, str) or not (
        value in ("auto", "cpu", "cuda") or (value.startswith("cuda:") and value[5:].isdigit())
    ):
        raise ConfigError(f"device must be auto, cpu, cuda or cuda:N, got {value!r}")
    return value


def validate(config: Mapping[str, Any]) -> dict[str, Any]:
    """A complete, checked copy of ``config`` (missing keys take the defaults); raises ConfigError."""
    if not isinstance(config, Mapping):
        raise ConfigError(f"a configuration must be a mapping of keys to values, got {type(config).__name__}")
    _unknown("", config, DEFAULTS)
    merged = merge(DEFAULTS, config)
    out: dict[str, Any] = {
        "joints": _int("joints", merged["joints"], 1),
        "arch": _choice("arch", merged["arch"], ARCHS),
        "preset": _choice("preset", merged["preset"], PRESETS),
        "timesteps": _int("timesteps", merged["timesteps"], 1),
        "n_envs": _int("n_envs", merged["n_envs"], 1),
        "seed": _int("seed", merged["seed"], 0),
        "eval_freq": _int("eval_freq", merged["eval_freq"], 0),
        "eval_episodes": _int("eval_episodes", merged["eval_episodes"], 1),
        "eval_seed": _int("eval_seed", merged["eval_seed"], 0, optional=True),
        "checkpoint_freq": _int("checkpoint_freq", merged["checkpoint_freq"], 0),
        "normalize": merged["normalize"],
        "device": _device(merged["device"]),
        "torch_threads": _int("torch_threads", merged["torch_threads"], 1, optional=True),
    }
    if not isinstance(out["normalize"], bool):
        raise ConfigError(f"normalize must be true or false, got {merged['normalize']!r}")

    ppo = merged["ppo"]
    if not isinstance(ppo, Mapping):
        raise ConfigError(f"ppo must be a mapping, got {ppo!r}")
    _unknown("ppo", ppo, PPO_DEFAULTS)
    out["ppo"] = {
        "learning_rate": _float("ppo.learning_rate", ppo["learning_rate"], 0.0),
        "n_steps": _int("ppo.n_steps", ppo["n_steps"], 1),
        "batch_size": _int("ppo.batch_size", ppo["batch_size"], 2),
        "n_epochs": _int("ppo.n_epochs", ppo["n_epochs"], 1),
        "gamma": _float("ppo.gamma", ppo["gamma"], 0.0, 1.0),
        "gae_lambda": _float("ppo.gae_lambda", ppo["gae_lambda"], 0.0, 1.0),
        "clip_range": _float("ppo.clip_range", ppo["clip_range"], 0.0),
        "ent_coef": _float("ppo.ent_coef", ppo["ent_coef"]),
        "vf_coef": _float("ppo.vf_coef", ppo["vf_coef"], 0.0),
        "max_grad_norm": _float("ppo.max_grad_norm", ppo["max_grad_norm"], 0.0),
    }
    if out["ppo"]["n_steps"] * out["n_envs"] < 2:
        raise ConfigError("ppo.n_steps * n_envs must be at least 2 (PPO needs a rollout of 2 steps)")

    env = merged["env"]
    if not isinstance(env, Mapping):
        raise ConfigError(f"env must be a mapping of SnakeEnv keywords, got {env!r}")
    _unknown("env", env, ENV_KEYS)
    out["env"] = copy.deepcopy(dict(env))
    check_env_kwargs(env_kwargs(out))
    return out


def check_env_kwargs(kwargs: Mapping[str, Any]) -> None:
    """Builds the env's configuration once, so that a bad value fails now and not after minutes."""
    from snakesim import _core

    try:
        _core.Env(env_config(**kwargs))
    except (TypeError, ValueError) as error:
        raise ConfigError(f"env: {error}") from None


def resolve(config: Mapping[str, Any]) -> dict[str, Any]:
    """``validate`` plus the values decided at run time (the evaluation seed), as saved with a run."""
    out = validate(config)
    if out["eval_seed"] is None:
        out["eval_seed"] = out["seed"] + EVAL_SEED_OFFSET
    return out


def env_kwargs(config: Mapping[str, Any]) -> dict[str, Any]:
    """The SnakeEnv / SnakeVecEnv keywords of a configuration."""
    return {"joints": config["joints"], "preset": config["preset"], **config.get("env", {})}


def merge(base: Mapping[str, Any], override: Mapping[str, Any]) -> dict[str, Any]:
    """``base`` updated by ``override``; the ``ppo`` and ``env`` tables merge key by key."""
    out = copy.deepcopy(dict(base))
    for key, value in override.items():
        if key in ("ppo", "env") and isinstance(value, Mapping) and isinstance(out.get(key), Mapping):
            out[key] = {**out[key], **copy.deepcopy(dict(value))}
        else:
            out[key] = copy.deepcopy(value)
    return out


def load_yaml(path: str | os.PathLike) -> dict[str, Any]:
    """The mapping in a YAML file (not yet validated); raises ConfigError with the file's name."""
    try:
        with open(path, encoding="utf-8") as f:
            data = yaml.safe_load(f)
    except FileNotFoundError:
        raise ConfigError(f"config file {os.fspath(path)} does not exist") from None
    except IsADirectoryError:
        raise ConfigError(f"config file {os.fspath(path)} is a directory") from None
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        problem = getattr(error, "problem", None) or type(error).__name__
        raise ConfigError(f"config file {os.fspath(path)} is not valid YAML{where}: {problem}") from None
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"cannot read config file {os.fspath(path)}: {error}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(
            f"config file {os.fspath(path)} must hold a mapping of keys, not {type(data).__name__}"
        )
    return data


def load(path: str | os.PathLike) -> dict[str, Any]:
    """A YAML file, validated (defaults filled in)."""
    try:
        return validate(load_yaml(path))
    except ConfigError as error:
        raise ConfigError(f"{os.fspath(path)}: {error}") from None


def dump(config: Mapping[str, Any]) -> str:
    """YAML text of a configuration, keys in the documented order."""
    return yaml.safe_dump(dict(config), sort_keys=False, default_flow_style=False)


def save(config: Mapping[str, Any], path: str | os.PathLike) -> None:
    with open(path, "w", encoding="utf-8") as f:
        f.write(dump(config))


def parse_set(items: list[str]) -> dict[str, Any]:
    """``["ppo.n_steps=64", "env.max_episode_steps=500"]`` -> nested overrides (values parsed as YAML)."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ConfigError(f"--set expects KEY=VALUE (e.g. ppo.n_steps=256), got {item!r}")
        try:
            value = yaml.safe_load(text) if text.strip() else None
        except yaml.YAMLError:
            raise ConfigError(f"--set {key}: cannot parse the value {text!r}") from None
        parts = key.split(".")
        table = out
        for part in parts[:-1]:
            if part not in ("ppo", "env"):
                raise ConfigError(f"--set {key}: only the ppo and env tables have sub-keys")
            table = table.setdefault(part, {})
        table[parts[-1]] = value
    return out
