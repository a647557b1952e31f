"""Trained agents: loading them (run directories, SB3 2.x zips, the paper's SB3 1.x zips) and running
evaluation episodes.

An :class:`Agent` is a policy plus what it needs to act in snakesim: the env keywords it was trained
with and, for runs trained with ``normalize: true``, the observation statistics.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import pickle
import re
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from snakesim import extras, runconfig
from snakesim.config import ENV_DEFAULTS, LIMITS

MODEL_FILE = "model.zip"
NATIVE_MODEL_FILE = "model.safetensors"
VECNORMALIZE_FILE = "vecnormalize.pkl"
CONFIG_FILE = "config.yaml"
CHECKPOINT_DIR = "checkpoints"
_CHECKPOINT = re.compile(r"^model_(\d+)_steps\.zip$")
_NATIVE_CHECKPOINT = re.compile(r"^model_(\d+)_steps\.safetensors$")


class AgentError(ValueError):
    """A model or run directory that cannot be used; the message says why."""


@dataclasses.dataclass
class ModelInfo:
    """What a zip's ``data`` tells without loading it."""

    sb3_version: str
    observation_dim: int
    action_dim: int
    legacy: bool  # saved by SB3 1.x with gym's spaces
    num_timesteps: int | None


@dataclasses.dataclass
class Agent:
    policy: Any  # stable_baselines3 ActorCriticPolicy
    path: str  # the zip
    env_kwargs: dict[str, Any]  # joints, preset and the rest of the env's keywords
    arch: str
    sb3_version: str
    num_timesteps: int | None
    obs_normalizer: Any = None  # a VecNormalize whose statistics normalise observations, or None
    config: dict[str, Any] | None = None  # the run's config.yaml, when loaded from a run directory
    # "sb3" (policy: an SB3 ActorCriticPolicy), "native" (a _core.NativePolicy) or "baseline" (a
    # snakesim.baselines.Controller)
    kind: str = "sb3"

    @property
    def joints(self) -> int:
        return int(self.env_kwargs["joints"])

    def act(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        if self.kind == "baseline":
            return self.policy.act(obs)
        if self.kind == "native":
            # The native policy normalises observations itself (with its saved statistics).
            return self.policy.act(np.ascontiguousarray(obs, dtype=np.float32), deterministic)
        if self.obs_normalizer is not None:
            obs = self.obs_normalizer.normalize_obs(obs)
        actions, _ = self.policy.predict(obs, deterministic=deterministic)
        return actions


def checkpoints(run_dir: str | os.PathLike, native: bool = False) -> list[tuple[int, Path]]:
    """The run's checkpoints as (timesteps, path), oldest first: SB3's zips, or the native trainer's
    safetensors files with ``native``."""
    folder = Path(run_dir) / CHECKPOINT_DIR
    if not folder.is_dir():
        return []
    pattern = _NATIVE_CHECKPOINT if native else _CHECKPOINT
    found = []
    for path in folder.iterdir():
        match = pattern.match(path.name)
        if match:
            found.append((int(match.group(1)), path))
    return sorted(found)


def _head(path: str | os.PathLike, size: int) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read(size)
    except OSError:
        return b""


def model_format(path: str | os.PathLike) -> str | None:
    """What a model file holds, judged by its first bytes rather than its name: ``"safetensors"`` (a
    snakesim model: an 8-byte header length, then the JSON header), ``"zip"`` (a Stable-Baselines3
    model), or None (neither, or unreadable)."""
    head = _head(path, 9)
    if head[:4] == b"PK\x03\x04":
        return "zip"
    if len(head) == 9 and head[8:9] == b"{" and 0 < int.from_bytes(head[:8], "little") < 1 << 32:
        return "safetensors"
    return None


def _first_line(error: BaseException, limit: int = 160) -> str:
    """The error's type and the start of its first line, for a one-line message."""
    lines = str(error).strip().splitlines()
    first = lines[0] if lines else ""
    return f"{type(error).__name__}: {first[:limit]}{'...' if len(first) > limit else ''}"


# Largest observation or action length a model may declare (a snake of MAX_JOINTS joints has ~1000).
_MAX_SPACE_SIZE = LIMITS["space_size"]


def load_normalizer(path: str | os.PathLike):
    """A ``VecNormalize`` saved beside a model, for evaluation (not updated); AgentError when the file
    is not one."""
    from stable_baselines3.common.vec_env import VecNormalize

    try:
        with open(path, "rb") as f:
            normalizer = pickle.load(f)
    except Exception as error:  # noqa: BLE001 - unpickling garbage fails in many ways
        raise AgentError(f"{os.fspath(path)} is not a VecNormalize pickle: {_first_line(error)}") from None
    if not isinstance(normalizer, VecNormalize):
        held = type(normalizer).__name__
        raise AgentError(f"{os.fspath(path)} is not a VecNormalize pickle (it holds {held})")
    normalizer.training = False
    return normalizer


def checkpoint_paths(run_dir: str | os.PathLike, timesteps: int) -> tuple[Path, Path]:
    folder = Path(run_dir) / CHECKPOINT_DIR
    return folder / f"model_{timesteps}_steps.zip", folder / f"vecnormalize_{timesteps}_steps.pkl"


def inspect_model(path: str | os.PathLike) -> ModelInfo:
    """Reads a SB3 zip's metadata; AgentError when it is not one."""
    try:
        with zipfile.ZipFile(path) as archive:
            names = set(archive.namelist())
            if "data" not in names or "policy.pth" not in names:
                raise AgentError(f"{os.fspath(path)} is not a Stable-Baselines3 model (no data/policy.pth)")
            data = json.loads(archive.read("data"))
            version = (
                archive.read("_stable_baselines3_version").decode().strip()
                if "_stable_baselines3_version" in names
                else "unknown"
            )
    except FileNotFoundError:
        raise AgentError(f"{os.fspath(path)} does not exist") from None
    except (zipfile.BadZipFile, json.JSONDecodeError, UnicodeDecodeError, IsADirectoryError):
        raise AgentError(f"{os.fspath(path)} is not a Stable-Baselines3 model zip") from None

    def shape(space: Any) -> list[int]:
        # gym (SB3 1.x) wrote "shape", gymnasium writes "_shape".
        return list(space["shape"] if "shape" in space else space["_shape"])

    try:
        obs_shape = shape(data["observation_space"])
        act_shape = shape(data["action_space"])
        space_type = str(data["observation_space"].get(":type:", ""))
    except (KeyError, TypeError, AttributeError):
        raise AgentError(f"{os.fspath(path)} has no Box observation/action spaces") from None
    flat = len(obs_shape) == 1 and len(act_shape) == 1
    if not flat or not all(type(n) is int and 0 < n <= _MAX_SPACE_SIZE for n in obs_shape + act_shape):
        raise AgentError(f"{os.fspath(path)}: expected flat Box spaces, got {obs_shape} and {act_shape}")
    legacy = version.startswith(("0.", "1.")) or "'gym." in space_type
    steps = data.get("num_timesteps")
    return ModelInfo(
        version, int(obs_shape[0]), int(act_shape[0]), legacy, steps if isinstance(steps, int) else None
    )


def _spaces(obs_dim: int, act_dim: int):
    from gymnasium import spaces

    return (
        spaces.Box(-np.inf, np.inf, (obs_dim,), dtype=np.float32),
        spaces.Box(-1.0, 1.0, (act_dim,), dtype=np.float32),
    )


def _load_legacy_policy(path: Path, info: ModelInfo, device: str):
    """An SB3 1.x zip (gym spaces, 1.x schedules) as an SB3 2.x ActorCriticPolicy.

    Nothing of the zip is unpickled: the spaces come from its JSON, every pickled field is replaced,
    and the weights are renamed where 1.x named them differently (shared layers).
    """
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.common.save_util import load_from_zip_file

    from snakesim.policies import convert_legacy_state_dict, parse_legacy_net_arch, policy_kwargs

    with zipfile.ZipFile(path) as archive:
        raw = json.loads(archive.read("data"))
    observation_space, action_space = _spaces(info.observation_dim, info.action_dim)
    replacements = {"observation_space": observation_space, "action_space": action_space}
    custom = {
        key: replacements.get(key)
        for key, value in raw.items()
        if isinstance(value, Mapping) and ":serialized:" in value
    }
    data, params, _ = load_from_zip_file(path, custom_objects=custom, device=device)
    kwargs = dict((data or {}).get("policy_kwargs") or {})
    net_arch = kwargs.pop("net_arch", None)
    if kwargs:
        raise AgentError(f"{path}: unsupported SB3 1.x policy_kwargs {sorted(kwargs)} (only net_arch)")
    if (data or {}).get("use_sde"):
        raise AgentError(f"{path}: SB3 1.x models with gSDE are not supported")
    try:
        arch, shared = parse_legacy_net_arch(net_arch)
    except ValueError as error:
        raise AgentError(f"{path}: {error}") from None
    policy = ActorCriticPolicy(
        observation_space,
        action_space,
        lambda _: 0.0,
        **policy_kwargs(arch, shared=shared or (128, 128)),
    ).to(device)
    try:
        policy.load_state_dict(convert_legacy_state_dict(params["policy"]))
    except RuntimeError as error:
        first = str(error).strip().splitlines()[0]
        raise AgentError(f"{path}: the weights do not fit the SB3 1.x network: {first}") from None
    policy.set_training_mode(False)
    return policy, arch


def _load_policy(path: Path, info: ModelInfo, device: str):
    if info.legacy:
        return _load_legacy_policy(path, info, device)
    from stable_baselines3 import PPO

    try:
        model = PPO.load(path, device=device)
    except Exception as error:  # noqa: BLE001 - a corrupt zip fails in torch or pickle in many ways
        raise AgentError(f"cannot load {path} as a PPO model: {_first_line(error)}") from None
    extractor = type(model.policy.features_extractor).__name__
    arch = "large" if extractor == "SharedMlp" else "small"
    return model.policy, arch


def load_agent(
    source: str | os.PathLike,
    *,
    joints: int | None = None,
    preset: str | None = None,
    env_overrides: Mapping[str, Any] | None = None,
    device: str = "cpu",
) -> Agent:
    """A run directory (its final model, else its latest checkpoint; its config.yaml), a bare SB3 zip
    or a native ``.safetensors`` model.

    For a run directory, ``joints`` and ``preset`` must agree with its config when given. For a bare
    zip, ``joints`` defaults to what the model's action space says and ``preset`` to ``paper``; a
    native model file names its own env.
    """
    if isinstance(source, str) and source.startswith(BASELINE_PREFIX):
        return _load_baseline(source.removeprefix(BASELINE_PREFIX), joints, preset, env_overrides)
    source = Path(source)
    config = None
    normalizer_path = None
    kind = model_format(source) if source.is_file() else None
    if source.is_file() and kind is None and source.suffix not in (".zip", ".safetensors"):
        raise AgentError(
            f"{source} is neither a snakesim model (safetensors) nor a Stable-Baselines3 model (zip): "
            f"it starts with {_head(source, 8)!r}"
        )
    native = kind == "safetensors" or (kind is None and source.suffix == ".safetensors")
    if source.is_dir() and (source / CONFIG_FILE).is_file():
        try:
            native = runconfig.load(source / CONFIG_FILE)["trainer"] == "native"
        except runconfig.ConfigError as error:
            raise AgentError(str(error)) from None
    if native:
        return _load_native_agent(source, joints=joints, preset=preset, env_overrides=env_overrides)
    if source.is_dir():
        config_path = source / CONFIG_FILE
        if not config_path.is_file():
            raise AgentError(f"{source} is not a run directory (no {CONFIG_FILE})")
        try:
            config = runconfig.load(config_path)
        except runconfig.ConfigError as error:
            raise AgentError(str(error)) from None
        model_path = source / MODEL_FILE
        normalizer_path = source / VECNORMALIZE_FILE
        if not model_path.is_file():
            found = checkpoints(source)
            if not found:
                raise AgentError(f"{source} has no {MODEL_FILE} and no checkpoints yet")
            steps, model_path = found[-1]
            normalizer_path = checkpoint_paths(source, steps)[1]
        for name, given in (("joints", joints), ("preset", preset)):
            if given is not None and given != config[name]:
                raise AgentError(f"{source} was trained with {name} {config[name]}, not {given}")
        env_kwargs = runconfig.env_kwargs(config)
    elif source.exists() or source.suffix == ".zip":
        model_path = source
        env_kwargs = {"joints": joints, "preset": preset or ENV_DEFAULTS["preset"]}
    else:
        raise AgentError(f"{source} does not exist (expected a run directory or a model .zip)")

    info = inspect_model(model_path)
    if env_kwargs["joints"] is None:
        env_kwargs["joints"] = info.action_dim
    env_kwargs.update(env_overrides or {})
    from snakesim.env import make_env

    try:
        probe = make_env(**env_kwargs)
    except (TypeError, ValueError) as error:
        raise AgentError(str(error)) from None
    obs_dim, act_dim = probe.observation_space.shape[0], probe.action_space.shape[0]
    if (info.observation_dim, info.action_dim) != (obs_dim, act_dim):
        raise AgentError(
            f"{model_path} expects {info.observation_dim} observations and {info.action_dim} actions, but "
            f"the env ({env_kwargs['joints']} joints) has {obs_dim} and {act_dim}: pass --joints "
            f"{info.action_dim} (or the observation it was trained with)"
        )
    extras.require("sb3", f"loading the Stable-Baselines3 model {model_path}")
    policy, arch = _load_policy(model_path, info, device)
    normalizer = None
    if normalizer_path is not None and normalizer_path.is_file():
        normalizer = load_normalizer(normalizer_path)
    return Agent(
        policy=policy,
        path=os.fspath(model_path),
        env_kwargs=env_kwargs,
        arch=config["arch"] if config else arch,
        sb3_version=info.sb3_version,
        num_timesteps=info.num_timesteps,
        obs_normalizer=normalizer,
        config=config,
    )


#: ``baseline:NAME`` names a hand-made controller of the goal task (snakesim.baselines).
BASELINE_PREFIX = "baseline:"


def _load_baseline(
    name: str, joints: int | None, preset: str | None, env_overrides: Mapping[str, Any] | None
) -> Agent:
    """A baseline controller in the goal task (``snakesim/SnakeGoal-v0``) with ``joints`` (5) and
    ``preset`` (paper)."""
    from snakesim import baselines
    from snakesim.config import GOAL_ENV_DEFAULTS
    from snakesim.env import make_env

    env_kwargs: dict[str, Any] = {
        "task": "goal",
        "joints": GOAL_ENV_DEFAULTS["joints"] if joints is None else joints,
        "preset": GOAL_ENV_DEFAULTS["preset"] if preset is None else preset,
        **(env_overrides or {}),
    }
    try:
        probe = make_env(**env_kwargs)
        baselines.check_env(probe.config)
        controller = baselines.Controller(name, probe.joints)
    except (TypeError, ValueError) as error:
        raise AgentError(str(error)) from None
    return Agent(
        policy=controller,
        path=BASELINE_PREFIX + name,
        env_kwargs=env_kwargs,
        arch="baseline",
        sb3_version="-",
        num_timesteps=None,
        kind="baseline",
    )


def _load_native_agent(
    source: Path,
    *,
    joints: int | None,
    preset: str | None,
    env_overrides: Mapping[str, Any] | None,
) -> Agent:
    """A native run directory (model.safetensors, else its latest checkpoint) or model file."""
    from snakesim import _core
    from snakesim.env import make_env

    config = None
    if source.is_dir():
        config = runconfig.load(source / CONFIG_FILE)
        model_path = source / NATIVE_MODEL_FILE
        if not model_path.is_file():
            found = checkpoints(source, native=True)
            if not found:
                raise AgentError(f"{source} has no {NATIVE_MODEL_FILE} and no checkpoints yet")
            model_path = found[-1][1]
    elif source.is_file():
        model_path = source
    else:
        raise AgentError(f"{source} does not exist (expected a run directory or a model file)")
    try:
        policy = _core.NativePolicy(os.fspath(model_path))
    except ValueError as error:
        raise AgentError(str(error)) from None
    env_kwargs: dict[str, Any] = {
        "joints": policy.joints,
        "preset": policy.preset,
        **json.loads(policy.env_json()),
    }
    for name, given in (("joints", joints), ("preset", preset)):
        if given is not None and given != env_kwargs[name]:
            raise AgentError(f"{model_path} was trained with {name} {env_kwargs[name]}, not {given}")
    env_kwargs.update(env_overrides or {})
    try:
        probe = make_env(**env_kwargs)
    except (TypeError, ValueError) as error:
        raise AgentError(str(error)) from None
    if (probe.observation_space.shape[0], probe.action_space.shape[0]) != (policy.obs_dim, policy.act_dim):
        raise AgentError(
            f"{model_path} expects {policy.obs_dim} observations and {policy.act_dim} actions, but the env "
            f"has {probe.observation_space.shape[0]} and {probe.action_space.shape[0]}"
        )
    return Agent(
        policy=policy,
        path=os.fspath(model_path),
        env_kwargs=env_kwargs,
        arch=policy.arch,
        sb3_version="native",
        num_timesteps=policy.timesteps,
        config=config,
        kind="native",
    )


@dataclasses.dataclass
class Episode:
    ret: float  # the return
    steps: int  # env steps
    success: bool  # reached the goal (terminated), not truncated
    seconds: float  # simulated time of the episode
    distance: float  # head displacement from the start to the end, metres
    path_length: float = 0.0  # length of the head's path in the plane, metres
    work: float = 0.0  # mechanical work of the motors, joules
    weight: float = 0.0  # the snake's weight m g, newtons

    @property
    def speed(self) -> float:
        """Mean speed, m/s: straight-line displacement over the episode's time."""
        return self.distance / self.seconds if self.seconds > 0 else 0.0

    @property
    def path_efficiency(self) -> float | None:
        """Straight-line displacement / path length (1: a straight line); None without a path."""
        return self.distance / self.path_length if self.path_length > 0 else None

    @property
    def cost_of_transport(self) -> float | None:
        """Mechanical energy / (m g displacement), dimensionless; None without displacement."""
        return self.work / (self.weight * self.distance) if self.distance > 0 and self.weight > 0 else None


def wilson_interval(successes: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """The Wilson score interval of a success rate (95 % by default)."""
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, centre - half), min(1.0, centre + half)


def _mean(values: list[float | None]) -> float | None:
    present = [v for v in values if v is not None]
    return float(np.mean(present)) if present else None


def run_episodes(
    act: Any,
    env_kwargs: Mapping[str, Any],
    episodes: int,
    seed: int,
    max_envs: int = 16,
) -> list[Episode]:
    """Runs ``episodes`` episodes of ``act(obs_batch) -> actions`` in a batched env of its own.

    Up to ``max_envs`` episodes run at once, env i seeded with ``seed + i`` (its later episodes
    continue its stream), so a seed gives the same episodes whatever the policy.
    """
    from snakesim import _core
    from snakesim.config import action_array, env_config
    from snakesim.env import make_env

    if episodes < 1:
        raise ValueError(f"episodes must be at least 1, got {episodes}")
    config = make_env(**env_kwargs).config
    step_seconds = config["snake"]["dt"] * config["physics_steps_per_env_step"]
    snake = config["snake"]
    weight = (snake["base_mass"] + snake["joints"] * snake["link_mass"]) * abs(snake["gravity"])
    m = min(episodes, max_envs)
    targets = [(episodes + i) // m for i in range(m)]  # as SB3's evaluate_policy splits them
    counts = [0] * m
    # The batched Rust env itself (as SnakeVecEnv steps it, without needing Stable-Baselines3): env i
    # is seeded with seed + i; each finished episode comes with its last observation and info.
    venv = _core.VecEnv(env_config(**env_kwargs), m)
    obs = venv.reset(seed)
    done_episodes: list[Episode] = []
    while counts != targets:
        obs, _, _, _, finals = venv.step(action_array(act(obs)))
        for i, final, info in sorted(finals, key=lambda done: done[0]):
            if counts[i] >= targets[i]:
                continue
            start = info["start"]
            done_episodes.append(
                Episode(
                    ret=float(info["episode_return"]),
                    steps=int(info["episode_step"]),
                    success=bool(info["success"]),
                    seconds=int(info["episode_step"]) * step_seconds,
                    distance=float(math.hypot(final[0] - start[0], final[1] - start[1])),
                    path_length=float(info["path_length"]),
                    work=float(info["work"]),
                    weight=weight,
                )
            )
            counts[i] += 1
    return done_episodes


def summarize(episodes: list[Episode]) -> dict[str, Any]:
    """Mean/std return, success rate (with its 95 % Wilson interval), mean steps and seconds to goal
    (successes only), mean speed, path efficiency and cost of transport (over all episodes)."""
    returns = np.array([e.ret for e in episodes])
    wins = [e for e in episodes if e.success]
    return {
        "episodes": len(episodes),
        "success_rate": len(wins) / len(episodes),
        "success_rate_ci95": list(wilson_interval(len(wins), len(episodes))),
        "mean_return": float(returns.mean()),
        "std_return": float(returns.std()),
        "mean_steps_to_goal": float(np.mean([e.steps for e in wins])) if wins else None,
        "mean_seconds_to_goal": float(np.mean([e.seconds for e in wins])) if wins else None,
        "mean_speed": float(np.mean([e.speed for e in episodes])),
        "mean_path_efficiency": _mean([e.path_efficiency for e in episodes]),
        "mean_cost_of_transport": _mean([e.cost_of_transport for e in episodes]),
        "mean_length": float(np.mean([e.steps for e in episodes])),
    }


def evaluate(agent: Agent, episodes: int, seed: int, deterministic: bool = True) -> dict[str, Any]:
    """:func:`summarize` of ``episodes`` episodes of the agent, with the per-episode figures."""
    done = run_episodes(lambda obs: agent.act(obs, deterministic), agent.env_kwargs, episodes, seed)
    out = summarize(done)
    out["per_episode"] = [
        {
            "return": e.ret,
            "steps": e.steps,
            "success": e.success,
            "seconds": e.seconds,
            "speed": e.speed,
            "path_efficiency": e.path_efficiency,
            "cost_of_transport": e.cost_of_transport,
        }
        for e in done
    ]
    return out
