"""The configuration of a training run.

One typed structure defines it: snake-rl's ``RunConfig`` (Rust), which holds every default (the paper's
Table 1 for PPO), limit and check; the ``snakesim`` and ``snake-cli`` commands and the YAML files read
it from there, and this module hands dictionaries to it. A configuration is built from layers, lowest
precedence first: the defaults, a YAML file (``--config``), then ``--set key=value`` (values in YAML
syntax) and the command's flags; mappings merge key by key. The resolved configuration is written to
``config.yaml`` in the run directory and reads back equal. Errors name the key path
(``ppo.learning_rate: must be positive, got 0``).

YAML layout (every key optional; unknown keys are errors)::

    trainer: native        # native (snake-rl, Rust) or sb3 (Stable-Baselines3)
    joints: 5              # N revolute joints (N + 1 cubes)
    arch: small            # small: pi/vf [64, 64]; large: shared [128, 128] then pi/vf [64, 64];
                           # or widths, as SB3's net_arch: {shared: [], pi: [256, 256], vf: [256, 256]}
                           # (a part left out takes small's)
    log_std_init: 0.0      # initial log standard deviation of the action noise (SB3's log_std_init)
    preset: paper          # paper (all cubes 0.06 kg) or snakebot-gym (links 1.0 kg, the paper's code)
    timesteps: 20000000
    n_envs: 16
    seed: 42
    eval_freq: 250000      # in total timesteps; 0: evaluate only at the end
    eval_episodes: 10
    eval_seed: null        # null: seed + 1000
    checkpoint_freq: 1000000   # in total timesteps; 0: only the final checkpoint
    normalize: false       # normalise observations and rewards as SB3's VecNormalize (the paper does not)
    device: auto           # sb3: auto, cpu, cuda or cuda:N
    torch_threads: null    # sb3: torch's CPU threads (null: torch's default)
    threads: null          # native: threads of the envs and updates (null: one per core)
    energy_ramp: null      # native: [from, to] timesteps over which env.reward.energy_weight rises from 0
    steer_assist: null     # native: {residual: true} and/or {near_goal: M}: baseline:steer shares the actions
    init: null             # native: fit the policy to a controller before PPO: {imitate: sine,
                           # steered_sine, gait or steer, hold: null ({amplitude: A, frequency: F}: gait
                           # and steer's held actions), steps: 65536, epochs: 10, batch_size: 256,
                           # learning_rate: 1e-3, log_std: -1.6, critic: false, anchor: null}; docs/guide.md
    ppo: {learning_rate: 3.0e-4, n_steps: 4096, batch_size: 64, n_epochs: 10, gamma: 0.99,
          gae_lambda: 0.95, clip_range: 0.2, clip_range_vf: null, normalize_advantage: true,
          ent_coef: 0.0, vf_coef: 0.5, max_grad_norm: 0.5, target_kl: null}
    env: {}                # more SnakeEnv keywords: goal, goal_radius, max_episode_steps, observation, ...

``learning_rate`` and ``clip_range`` also take ``lin_<value>``: a linear decay to 0 over the run.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from snakesim import _core
from snakesim.envs.config import plain
from snakesim.files import FileError, read_text, rewrite_atomically

#: Every key with its default, from Rust.
DEFAULTS: dict[str, Any] = json.loads(_core.run_config_defaults())
ARCHS: tuple[str, ...] = tuple(_core.ARCHS)
#: The run configuration's command-line flags (key, flag, value kind, choices, help), from snake-rl:
#: ``snakesim train`` builds its flags from them, as ``snake-cli train`` does.
FLAGS: list[dict[str, Any]] = json.loads(_core.run_config_flags())
TRAINERS: tuple[str, ...] = tuple(next(f["choices"] for f in FLAGS if f["key"] == "trainer"))
#: Keys that define what is learnt; --resume refuses to change them.
IDENTITY_KEYS: tuple[str, ...] = tuple(_core.IDENTITY_KEYS)
EVAL_SEED_OFFSET: int = _core.EVAL_SEED_OFFSET


class ConfigError(ValueError):
    """A configuration that cannot be used; the message names the key and what is wrong."""


def arch_label(arch: str | Mapping[str, Any]) -> str:
    """A configuration's ``arch`` in words, as runs and plots name it: ``small``, ``large`` or the widths
    (``pi [256, 256], vf [256, 256]``)."""
    return _rust(_core.arch_label, json.dumps(plain(arch, "arch")))


def _rust(call, *args):
    try:
        return call(*args)
    except (TypeError, ValueError) as error:
        raise ConfigError(str(error)) from None


def _texts(layers: Sequence[Mapping[str, Any]]) -> list[str]:
    texts = []
    for layer in layers:
        if not isinstance(layer, Mapping):
            raise ConfigError(
                f"a configuration must be a mapping of keys to values, got {type(layer).__name__}"
            )
        try:
            texts.append(json.dumps(plain(dict(layer), "config")))
        except (TypeError, ValueError) as error:
            raise ConfigError(str(error)) from None
    return texts


def merge(*layers: Mapping[str, Any]) -> dict[str, Any]:
    """The layers merged key by key at every depth (later ones win), without defaults or checks. Widths
    of some parts of the network (``arch: {pi: [256]}``) over a named one (``large``) keep its other
    parts (snake-rl's ``merge_layer``)."""
    return json.loads(_rust(_core.merge_layers, _texts(layers)))


def resolve_layers(layers: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The complete, checked configuration of ``layers`` over the defaults (lowest first)."""
    return json.loads(_rust(_core.resolve_run_config, _texts(layers)))


def validate(config: Mapping[str, Any]) -> dict[str, Any]:
    """A complete, checked copy of ``config`` (missing keys take the defaults); raises ConfigError."""
    return resolve_layers([config])


def resolve(config: Mapping[str, Any]) -> dict[str, Any]:
    """``validate`` plus the values decided at run time (the evaluation seed), as saved with a run."""
    out = validate(config)
    if out["eval_seed"] is None:
        out["eval_seed"] = out["seed"] + EVAL_SEED_OFFSET
    return out


def env_kwargs(config: Mapping[str, Any]) -> dict[str, Any]:
    """The SnakeEnv / SnakeVecEnv keywords of a configuration."""
    return {"joints": config["joints"], "preset": config["preset"], **config.get("env", {})}


def load_yaml(path: str | os.PathLike, what: str = "config file") -> dict[str, Any]:
    """The mapping in a YAML file (not yet validated), parsed by the same YAML rules as ``--set``;
    raises ConfigError with ``what`` (``config file``, a flag) and the file's name."""
    name = os.fspath(path)
    try:
        text = read_text(path, "config_bytes")
    except FileError as error:
        raise ConfigError(f"{what} {error}") from None
    except FileNotFoundError:
        raise ConfigError(f"{what} {name} does not exist") from None
    except IsADirectoryError:
        raise ConfigError(f"{what} {name} is a directory") from None
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"cannot read {what} {name}: {error}") from None
    try:
        data = json.loads(_core.parse_yaml(text))
    except ValueError as error:
        raise ConfigError(f"{what} {name}: {error}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{what} {name} must hold a mapping of keys, not {type(data).__name__}")
    return data


def load(path: str | os.PathLike) -> dict[str, Any]:
    """A YAML file, validated (defaults filled in)."""
    try:
        return validate(load_yaml(path))
    except ConfigError as error:
        raise ConfigError(f"{os.fspath(path)}: {error}") from None


def dump(config: Mapping[str, Any]) -> str:
    """YAML text of a configuration, keys in the documented order."""
    return _rust(_core.run_config_yaml, json.dumps(dict(config)))


def save(config: Mapping[str, Any], path: str | os.PathLike) -> None:
    """Writes config.yaml whole (readers of a run being trained never see half of it)."""
    text = dump(config)
    rewrite_atomically(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def parse_set(items: list[str]) -> dict[str, Any]:
    """``["ppo.n_steps=64", "env.reward.progress_weight=1"]`` -> nested overrides (values parsed as YAML)."""
    return json.loads(_rust(_core.parse_overrides, list(items)))


def schedule(value: float | str):
    """A learning rate or clip range of the configuration as SB3 takes it: a number, or for
    ``lin_<v>`` a function of the remaining progress (1 -> 0)."""
    if isinstance(value, str):
        initial = float(value.removeprefix("lin_"))
        return lambda progress_remaining: initial * progress_remaining
    return value
