"""Trained agents: loading them (run directories, SB3 2.x zips, the paper's SB3 1.x zips) and running
evaluation episodes.

An :class:`Agent` is a policy plus what it needs to act in snakesim: the env keywords it was trained
with and, for runs trained with ``normalize: true``, the observation statistics.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pickle
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from snakesim import extras
from snakesim.envs.config import ENV_DEFAULTS
from snakesim.limits import LIMITS
from snakesim.runs import config as runconfig
from snakesim.runs.rundir import (
    CONFIG_FILE,
    MODEL_FILE,
    NATIVE_MODEL_FILE,
    VECNORMALIZE_FILE,
    checkpoint_paths,
    checkpoints,
)


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
    # snakesim.agents.baselines.Controller)
    kind: str = "sb3"

    @property
    def joints(self) -> int:
        """The driven joints: the snake's, or a robot's movable joints (whatever ``joints`` says)."""
        if self.env_kwargs.get("robot"):
            from snakesim import _core
            from snakesim.envs.config import env_config

            return int(_core.Env(env_config(**self.env_kwargs)).joints)
        return int(self.env_kwargs["joints"])

    @property
    def label(self) -> str:
        """What acts, in words: ``PPO-small`` or ``baseline:steer``."""
        return self.path if self.kind == "baseline" else f"PPO-{self.arch}"

    @property
    def body(self) -> str:
        """The body it drives, in words: ``10 joints`` or ``robot robots/yaw-pitch-16.yaml (15 joints)``."""
        robot = self.env_kwargs.get("robot")
        return f"{self.joints} joints" if not robot else f"robot {robot} ({self.joints} joints)"

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

    from snakesim.runs.policies import convert_legacy_state_dict, parse_legacy_net_arch, policy_kwargs

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
    task: str = "goal",
    env_from: str | os.PathLike | None = None,
) -> Agent:
    """A run directory (its final model, else its latest checkpoint; its config.yaml), a bare SB3 zip
    or a native ``.safetensors`` model.

    For a run directory, ``joints`` and ``preset`` must agree with its config when given. For a bare
    zip, ``joints`` defaults to what the model's action space says and ``preset`` to ``paper``; a
    native model file names its own env. A baseline (``baseline:NAME``) runs in ``task``'s env
    (``goal``, ``pegs``, ``rough``), or with ``env_from`` (a model or run directory) in exactly the env
    recorded there.
    """
    if isinstance(source, str) and source.startswith(BASELINE_PREFIX):
        return _load_baseline(
            source.removeprefix(BASELINE_PREFIX), joints, preset, env_overrides, task=task, env_from=env_from
        )
    if task != "goal" or env_from is not None:
        raise AgentError(
            "--env and --env-from are for baselines: a model evaluates on the env it was trained on"
        )
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
    from snakesim.envs.env import make_env

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
        arch=runconfig.arch_label(config["arch"]) if config else arch,
        sb3_version=info.sb3_version,
        num_timesteps=info.num_timesteps,
        obs_normalizer=normalizer,
        config=config,
    )


#: ``baseline:NAME`` names a hand-made controller of the goal task (snakesim.agents.baselines).
BASELINE_PREFIX = "baseline:"


def env_kwargs_of(source: str | os.PathLike) -> dict[str, Any]:
    """The env keywords recorded in a model's metadata or a run directory (what :func:`load_agent`
    would evaluate the agent on), for running a baseline on exactly that env."""
    if isinstance(source, str) and source.startswith(BASELINE_PREFIX):
        raise AgentError(f"--env-from needs a model or a run directory, not {source}")
    return dict(load_agent(source).env_kwargs)


def _load_baseline(
    name: str,
    joints: int | None,
    preset: str | None,
    env_overrides: Mapping[str, Any] | None,
    *,
    task: str = "goal",
    env_from: str | os.PathLike | None = None,
) -> Agent:
    """A baseline controller in ``task``'s env (the goal task, ``snakesim/SnakeGoal-v0``, unless
    told) with ``joints`` (5) and ``preset`` (paper), or in exactly the env recorded in
    ``env_from`` (a model or a run directory)."""
    from snakesim.agents import baselines
    from snakesim.envs.config import GOAL_ENV_DEFAULTS
    from snakesim.envs.env import make_env

    if env_from is not None:
        if joints is not None or preset is not None:
            raise AgentError(f"--env-from takes joints and preset from {os.fspath(env_from)}: leave them out")
        env_kwargs: dict[str, Any] = baselines.plain_gait(
            {**env_kwargs_of(env_from), **(env_overrides or {})}
        )
    else:
        env_kwargs = {
            "task": task,
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
    from snakesim.envs.env import make_env

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
