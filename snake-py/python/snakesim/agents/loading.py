"""Trained agents: loading them (native models, run directories, SB3 2.x zips, the paper's SB3 1.x
zips, baselines) and what they need to act.

An :class:`Agent` is a policy plus what it needs to act in snakesim: the env keywords it was trained
with and, for SB3 models trained with ``normalize: true``, the observation statistics.

:func:`load_agent` finds out once what a path holds (:func:`_locate`) and hands it to the one reader of
that format, which reads each file once. Loading never runs code from a file: a native model is JSON
and tensors parsed by Rust; of an SB3 zip only the JSON ``data`` (as plain data: no pickled entry is
unpickled) and ``policy.pth`` (``torch.load(weights_only=True)``) are read, and the network is rebuilt
from the shapes of its weights; VecNormalize statistics are unpickled through an allow-list
(:mod:`snakesim.agents.safe_pickle`). See docs/formats.md.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import os
import re
import stat
import sys
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from snakesim import extras
from snakesim.envs.config import ENV_DEFAULTS
from snakesim.files import FileError, check_size, open_regular, read_bytes
from snakesim.limits import LIMITS
from snakesim.runs import config as runconfig
from snakesim.runs.rundir import (
    CONFIG_FILE,
    EXPORTED_STATISTICS_SUFFIX,
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
    # The files it was read from (model, config.yaml, statistics): what a command must not overwrite.
    files: tuple[str, ...] = ()
    # baseline:steer's share of its actions (a _core.SteerAssist), when it was trained with one:
    # applied in act, so whatever steps the env with act's actions runs the agent as it was trained.
    steer_assist: Any = None

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
        from snakesim.envs.config import file_label

        robot = self.env_kwargs.get("robot")
        return f"{self.joints} joints" if not robot else f"robot {file_label(robot)} ({self.joints} joints)"

    def act(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        """The env's actions for a batch of observations: the policy's own, or with a
        ``steer_assist``, its composition of them (float64)."""
        if self.kind == "baseline":
            return self.policy.act(obs)
        actions = self.own_actions(obs, deterministic)
        if self.steer_assist is None:
            return actions
        obs = np.ascontiguousarray(np.atleast_2d(obs), dtype=np.float32)
        return self.steer_assist.apply(obs, np.atleast_2d(actions))

    def restart(self, env: int | None = None) -> None:
        """Row ``env`` of the batch starts a new episode (every row, with None): a baseline with a
        clock (``baseline:sine``) restarts it; policies have no state between steps."""
        restart = getattr(self.policy, "restart", None) if self.kind == "baseline" else None
        if restart is not None:
            restart(env)

    def own_actions(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        """The policy's own actions (before any ``steer_assist``), in [-1, 1]."""
        if self.kind == "native":
            # The native policy normalises observations itself (with its saved statistics).
            return self.policy.act(np.ascontiguousarray(obs, dtype=np.float32), deterministic)
        if self.obs_normalizer is not None:
            obs = self.obs_normalizer.normalize_obs(obs)
        actions, _ = self.policy.predict(obs, deterministic=deterministic)
        return actions


#: ``baseline:NAME`` names a hand-made controller (snakesim.agents.baselines).
BASELINE_PREFIX = "baseline:"
#: The entry of an SB3 zip's ``data`` where ``snakesim export`` records the env keywords (plain JSON).
EXPORTED_ENV_KEY = "snakesim_env_kwargs"
#: The entry where it records a native model's ``steer_assist`` (plain JSON), when it has one.
EXPORTED_ASSIST_KEY = "snakesim_steer_assist"
#: The entry where snakesim's SB3 trainer and ``snakesim export`` record the texts of the env's robot
#: and world files (plain JSON, a native model's ``env_files``: docs/formats.md).
RECORDED_FILES_KEY = "snakesim_env_files"


def _note(lines: list[str]) -> None:
    """Tells the user what loading found (a robot file that changed since training), one line each."""
    for line in lines:
        print(f"note: {line}", file=sys.stderr)


def bind_assist(where: Path | str, assist: Any, env_kwargs: Mapping[str, Any]) -> Any:
    """A recorded ``steer_assist`` (JSON text or a mapping) bound to the env of ``env_kwargs`` (a
    ``_core.SteerAssist``), or None when there is none."""
    from snakesim import _core
    from snakesim.envs.config import env_config

    if assist is None:
        return None
    text = assist if isinstance(assist, str) else json.dumps(assist)
    try:
        return _core.SteerAssist.from_json(text, env_config(**env_kwargs))
    except (TypeError, ValueError) as error:
        raise AgentError(f"{where}: {error}") from None


# Largest observation or action length a model may declare (a snake of MAX_JOINTS joints has ~1000).
_MAX_SPACE_SIZE = LIMITS["space_size"]


def _first_line(error: BaseException, limit: int = 160) -> str:
    """The error's type and the start of its first line, for a one-line message."""
    lines = str(error).strip().splitlines()
    first = lines[0] if lines else ""
    return f"{type(error).__name__}: {first[:limit]}{'...' if len(first) > limit else ''}"


# -- what a path holds ----------------------------------------------------------------------------
def _sniff(path: Path) -> str | None:
    """``"safetensors"``, ``"zip"`` or None, by the first bytes of a regular file; OSError and
    FileError pass through."""
    with open_regular(path, "model_bytes") as f:
        head = f.read(9)
    if head[:4] == b"PK\x03\x04":
        return "zip"
    if len(head) == 9 and head[8:9] == b"{" and 0 < int.from_bytes(head[:8], "little") < 1 << 32:
        return "safetensors"
    return None


def model_format(path: str | os.PathLike) -> str | None:
    """What a model file holds, judged by its first bytes rather than its name: ``"safetensors"`` (a
    snakesim model: an 8-byte header length, then the JSON header), ``"zip"`` (a Stable-Baselines3
    model), or None (neither, or unreadable)."""
    try:
        return _sniff(Path(path))
    except (OSError, FileError):
        return None


def normalizer_beside(zip_path: str | os.PathLike) -> Path | None:
    """The VecNormalize statistics that belong to an SB3 zip, when they are there: ``NAME_vecnormalize.pkl``
    beside ``NAME.zip`` (what ``snakesim export`` writes), or a run directory's own (``vecnormalize.pkl``
    beside ``model.zip``, ``vecnormalize_<T>_steps.pkl`` beside ``model_<T>_steps.zip``)."""
    path = Path(zip_path)
    candidates = [path.with_name(path.stem + EXPORTED_STATISTICS_SUFFIX)]
    if path.name == MODEL_FILE:
        candidates.append(path.with_name(VECNORMALIZE_FILE))
    match = re.fullmatch(r"model_(\d+)_steps\.zip", path.name)
    if match:
        candidates.append(path.with_name(f"vecnormalize_{match.group(1)}_steps.pkl"))
    return next((c for c in candidates if c.is_file()), None)


@dataclasses.dataclass(frozen=True)
class _Located:
    """What :func:`load_agent` was given, found out once: the reader's format and its files."""

    format: str  # "native" or "sb3"
    model: Path
    config: dict[str, Any] | None = None  # a run directory's config.yaml
    normalizer: Path | None = None  # an SB3 model's VecNormalize statistics
    run: Path | None = None  # the run directory

    @property
    def files(self) -> tuple[str, ...]:
        """Every file the agent is read from."""
        config = None if self.run is None else self.run / CONFIG_FILE
        return tuple(os.fspath(f) for f in (self.model, config, self.normalizer) if f is not None)


def _locate(source: Path) -> _Located:
    try:
        mode = os.stat(source).st_mode
    except FileNotFoundError:
        raise AgentError(f"{source} does not exist (expected a run directory or a model .zip)") from None
    except OSError as error:
        raise AgentError(f"cannot read {source}: {error.strerror or error}") from None
    if stat.S_ISDIR(mode):
        return _locate_in_run(source)
    if not stat.S_ISREG(mode):
        raise AgentError(f"{source}: not a regular file (a device, FIFO or socket)")
    try:
        kind = _sniff(source)
    except FileError as error:
        raise AgentError(str(error)) from None
    except OSError as error:
        raise AgentError(f"cannot read {source}: {error.strerror or error}") from None
    # A file that is neither by content is judged by its name, for the reader's own error.
    kind = kind or {".zip": "zip", ".safetensors": "safetensors"}.get(source.suffix)
    if kind == "safetensors":
        return _Located("native", source)
    if kind == "zip":
        return _Located("sb3", source, normalizer=normalizer_beside(source))
    raise AgentError(
        f"{source} is neither a snakesim model (safetensors) nor a Stable-Baselines3 model (zip)"
    )


def _locate_in_run(run: Path) -> _Located:
    """A run directory: its config.yaml, and its final model, else its latest checkpoint."""
    config_path = run / CONFIG_FILE
    if not config_path.is_file():
        raise AgentError(f"{run} is not a run directory (no {CONFIG_FILE})")
    try:
        config = runconfig.load(config_path)
    except runconfig.ConfigError as error:
        raise AgentError(str(error)) from None
    native = config["trainer"] == "native"
    model = run / (NATIVE_MODEL_FILE if native else MODEL_FILE)
    normalizer = run / VECNORMALIZE_FILE
    if not model.is_file():
        found = checkpoints(run, native=native)
        if not found:
            raise AgentError(f"{run} has no {model.name} and no checkpoints yet")
        steps, model = found[-1]
        normalizer = checkpoint_paths(run, steps)[1]
    if native:
        return _Located("native", model, config, run=run)
    return _Located("sb3", model, config, normalizer if normalizer.is_file() else None, run)


# -- loading --------------------------------------------------------------------------------------
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
    (with the statistics beside it, see :func:`normalizer_beside`) or a native ``.safetensors`` model.

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
    located = _locate(Path(source))
    if located.format == "native":
        return _read_native(located, joints, preset, env_overrides)
    return _read_sb3(located, joints, preset, env_overrides, device)


def recorded_env_files(model: str | os.PathLike) -> Any:
    """The robot and world files an SB3 zip records (``snakesim_env_files``), or None; read as plain
    JSON, nothing unpickled. AgentError when the file is not an SB3 model."""
    return _read_zip(Path(model)).data.get(RECORDED_FILES_KEY)


def env_kwargs_of(source: str | os.PathLike) -> dict[str, Any]:
    """The env keywords recorded in a model's metadata or a run directory (what :func:`load_agent`
    would evaluate the agent on), for running a baseline on exactly that env."""
    if isinstance(source, str) and source.startswith(BASELINE_PREFIX):
        raise AgentError(f"--env-from needs a model or a run directory, not {source}")
    return dict(load_agent(source).env_kwargs)


def _agreed_env(
    where: Path | str,
    recorded: dict[str, Any],
    joints: int | None,
    preset: str | None,
    overrides: Mapping[str, Any] | None,
) -> dict[str, Any]:
    """The recorded env keywords, with ``overrides``; AgentError when ``joints`` or ``preset`` are
    given and differ from the recorded ones."""
    for name, given in (("joints", joints), ("preset", preset)):
        if given is not None and given != recorded.setdefault(name, given):
            raise AgentError(f"{where} was trained with {name} {recorded[name]}, not {given}")
    return {**recorded, **(overrides or {})}


def _check_env(model: Path, env_kwargs: dict[str, Any], obs_dim: int, act_dim: int, hint: str = "") -> None:
    """AgentError unless the env of ``env_kwargs`` has the model's observation and action sizes."""
    from snakesim.envs.env import make_env

    try:
        probe = make_env(**env_kwargs)
    except (TypeError, ValueError) as error:
        raise AgentError(str(error)) from None
    has = (probe.observation_space.shape[0], probe.action_space.shape[0])
    if has != (obs_dim, act_dim):
        raise AgentError(
            f"{model} expects {obs_dim} observations and {act_dim} actions, but the env "
            f"({probe.joints} joints) has {has[0]} and {has[1]}{hint}"
        )


def _read_native(
    located: _Located, joints: int | None, preset: str | None, overrides: Mapping[str, Any] | None
) -> Agent:
    """A native model (a ``.safetensors`` file, or a native run's): Rust reads and checks it."""
    from snakesim import _core

    try:
        policy = _core.NativePolicy(os.fspath(located.model))
    except ValueError as error:
        raise AgentError(str(error)) from None
    _note(policy.notes)
    recorded = {"joints": policy.joints, "preset": policy.preset, **json.loads(policy.env_json())}
    env_kwargs = _agreed_env(located.model, recorded, joints, preset, overrides)
    _check_env(located.model, env_kwargs, policy.obs_dim, policy.act_dim)
    return Agent(
        policy=policy,
        path=os.fspath(located.model),
        env_kwargs=env_kwargs,
        arch=policy.arch,
        sb3_version="native",
        num_timesteps=policy.timesteps,
        config=located.config,
        kind="native",
        files=located.files,
        steer_assist=bind_assist(located.model, policy.steer_assist_json(), env_kwargs),
    )


def _read_sb3(
    located: _Located,
    joints: int | None,
    preset: str | None,
    overrides: Mapping[str, Any] | None,
    device: str,
) -> Agent:
    """An SB3 zip (2.x, or the paper's 1.x), bare or a run's, with its statistics when it has them."""
    model = located.model
    archive = _read_zip(model)
    info = archive.info
    hint = ""
    recorded = archive.data.get(EXPORTED_ENV_KEY)
    if located.config is not None:
        recorded = runconfig.env_kwargs(located.config)
        env_kwargs = _agreed_env(model.parent, recorded, joints, preset, overrides)
    elif isinstance(recorded, dict) and ":serialized:" not in recorded:  # by snakesim export
        env_kwargs = _agreed_env(model, dict(recorded), joints, preset, overrides)
    else:
        bare_joints = info.action_dim if joints is None else joints
        env_kwargs = {"joints": bare_joints, "preset": preset or ENV_DEFAULTS["preset"], **(overrides or {})}
        hint = f": pass --joints {info.action_dim} (or the observation it was trained with)"
    if not hint:
        # The recorded robot and world files, where the env keywords are known (not guessed).
        env_kwargs = _recorded_files(model, env_kwargs, archive.data.get(RECORDED_FILES_KEY))
    _check_env(model, env_kwargs, info.observation_dim, info.action_dim, hint)
    extras.require("sb3", f"loading the Stable-Baselines3 model {model}")
    policy, arch = _sb3_policy(model, archive, device)
    normalizer = None
    if located.normalizer is not None:
        normalizer = load_normalizer(located.normalizer, info.observation_dim)
        _check_statistics(located.normalizer, normalizer, info.observation_dim)
    return Agent(
        policy=policy,
        path=os.fspath(model),
        env_kwargs=env_kwargs,
        arch=runconfig.arch_label(located.config["arch"]) if located.config else arch,
        sb3_version=info.sb3_version,
        num_timesteps=info.num_timesteps,
        obs_normalizer=normalizer,
        config=located.config,
        files=located.files,
        steer_assist=bind_assist(model, archive.data.get(EXPORTED_ASSIST_KEY), env_kwargs),
    )


def _recorded_files(model: Path, env_kwargs: dict[str, Any], records: Any) -> dict[str, Any]:
    """``env_kwargs`` with the robot and world files an SB3 zip records (``snakesim_env_files``) in
    place of those that changed since training, with a note for each (as a native model's). A robot
    or world path without a record is refused: a model's files come from its record, never from a
    path it names alone."""
    from snakesim.envs.config import apply_env_files

    if records is None:
        records = {}
    if not isinstance(records, dict) or ":serialized:" in records:
        raise AgentError(f"{model}: its {RECORDED_FILES_KEY} is not a JSON mapping")
    try:
        env_kwargs, notes = apply_env_files(env_kwargs, records)
    except (TypeError, ValueError) as error:
        raise AgentError(f"{model}: {error}") from None
    _note([f"{model}: {line}" for line in notes])
    return env_kwargs


# -- SB3 zips -------------------------------------------------------------------------------------
@dataclasses.dataclass
class _Zip:
    """The members of an SB3 zip that loading reads: ``data`` as plain JSON (no entry unpickled) and
    ``policy.pth`` as bytes."""

    info: ModelInfo
    data: dict[str, Any]
    weights: bytes


def _member(archive: zipfile.ZipFile, name: str, limit: str, path: Path) -> bytes:
    # The sizes in the zip's directory bound what is decompressed: zipfile stops at the stated size
    # (and fails the CRC when the data is longer), so a zip bomb is refused before it is inflated.
    check_size(archive.getinfo(name).file_size, limit, f"{path}: member {name}")
    return archive.read(name)


def _read_zip(path: Path) -> _Zip:
    """The zip's ``data`` and ``policy.pth``, read once; AgentError when it is not an SB3 model."""
    try:
        raw = read_bytes(path, "model_bytes")
    except FileError as error:
        raise AgentError(str(error)) from None
    except FileNotFoundError:
        raise AgentError(f"{path} does not exist") from None
    except IsADirectoryError:
        raise AgentError(f"{path} is not a Stable-Baselines3 model zip") from None
    except OSError as error:
        raise AgentError(f"cannot read {path}: {error.strerror or error}") from None
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as archive:
            names = set(archive.namelist())
            if "data" not in names or "policy.pth" not in names:
                raise AgentError(f"{path} is not a Stable-Baselines3 model (no data/policy.pth)")
            data = json.loads(_member(archive, "data", "config_bytes", path))
            weights = _member(archive, "policy.pth", "model_bytes", path)
            version = "unknown"
            if "_stable_baselines3_version" in names:
                version = _member(archive, "_stable_baselines3_version", "config_bytes", path).decode()
                version = version.strip()
    except FileError as error:
        raise AgentError(str(error)) from None
    except AgentError:
        raise
    except (zipfile.BadZipFile, zlib.error, EOFError, NotImplementedError, RuntimeError, ValueError):
        # A damaged directory or member, an unknown compression, an encrypted member, bad JSON or text.
        raise AgentError(f"{path} is not a Stable-Baselines3 model zip") from None
    if not isinstance(data, dict):
        raise AgentError(f"{path} is not a Stable-Baselines3 model zip (its data is not a mapping)")
    return _Zip(_model_info(path, data, version[:40]), data, weights)


def _model_info(path: Path, data: dict[str, Any], version: str) -> ModelInfo:
    def shape(space: Any) -> list[int]:
        # gym (SB3 1.x) wrote "shape", gymnasium writes "_shape".
        return list(space["shape"] if "shape" in space else space["_shape"])

    try:
        obs_shape = shape(data["observation_space"])
        act_shape = shape(data["action_space"])
        space_type = str(data["observation_space"].get(":type:", ""))
    except (KeyError, TypeError, AttributeError):
        raise AgentError(f"{path} has no Box observation/action spaces") from None
    flat = len(obs_shape) == 1 and len(act_shape) == 1
    if not flat or not all(type(n) is int and 0 < n <= _MAX_SPACE_SIZE for n in obs_shape + act_shape):
        shown = str(obs_shape)[:40], str(act_shape)[:40]
        raise AgentError(f"{path}: expected flat Box spaces, got {shown[0]} and {shown[1]}")
    legacy = version.startswith(("0.", "1.")) or "'gym." in space_type
    steps = data.get("num_timesteps")
    return ModelInfo(
        version, int(obs_shape[0]), int(act_shape[0]), legacy, steps if type(steps) is int else None
    )


def inspect_model(path: str | os.PathLike) -> ModelInfo:
    """Reads a SB3 zip's metadata; AgentError when it is not one."""
    return _read_zip(Path(path)).info


def safe_custom_objects(path: str | os.PathLike, known: Mapping[str, Any]) -> dict[str, Any]:
    """``custom_objects`` for SB3's ``PPO.load(path)`` that replace every pickled entry of the zip's
    ``data`` (so SB3 unpickles none of them): by ``known``'s value where it has one, else by None
    (what SB3 rebuilds when it starts learning: the last observation, the episode buffers)."""
    data = _read_zip(Path(path)).data
    pickled = [key for key, value in data.items() if isinstance(value, Mapping) and ":serialized:" in value]
    return {key: known.get(key) for key in pickled}


# The activations SB3 policies are built with, by the name `data` records for policy_kwargs'
# activation_fn ("<class 'torch.nn.modules.activation.Tanh'>"); looked up in torch.nn, never unpickled.
_ACTIVATIONS = ("Tanh", "ReLU", "LeakyReLU", "ELU", "GELU", "SiLU", "Sigmoid")
_EXTRACTORS = {
    "<class 'stable_baselines3.common.torch_layers.FlattenExtractor'>",
    "<class 'snakesim.runs.policies.SharedMlp'>",
}
# Where the layers of each part of the network live in an SB3 2.x state dict (Linear, activation, ...).
_PARTS = {
    "shared": "features_extractor.shared_net",
    "pi": "mlp_extractor.policy_net",
    "vf": "mlp_extractor.value_net",
}


def _sb3_policy(path: Path, archive: _Zip, device: str):
    """The zip's policy as an SB3 2.x ActorCriticPolicy with snakesim's networks, and its arch label.

    The network is rebuilt from the shapes of the weights (widths of the shared trunk and of the
    heads) and the plain parts of ``policy_kwargs``; SB3 1.x weights are renamed where 1.x named them
    differently (shared layers).
    """
    import torch
    from stable_baselines3.common.policies import ActorCriticPolicy

    from snakesim.runs.policies import convert_legacy_state_dict, policy_kwargs

    info, data = archive.info, archive.data
    if data.get("use_sde"):
        raise AgentError(f"{path}: models with gSDE (use_sde) are not supported")
    where = f"{path}: member policy.pth"
    state = _weights(where, archive.weights, device)
    if info.legacy:
        state = convert_legacy_state_dict(state)
    activation = _activation(path, data.get("policy_kwargs"))
    widths = _widths(where, state, info)
    try:
        label = runconfig.arch_label(widths)
    except runconfig.ConfigError as error:
        raise AgentError(f"{path}: its network: {error}") from None
    # In float32, as the network holds them (a float64 weight of 1e300 becomes infinite there).
    state = {name: tensor.to(torch.float32) for name, tensor in state.items()}
    for name, tensor in state.items():
        if not bool(torch.isfinite(tensor).all()):
            raise AgentError(f"{where}: tensor {_tensor_name(name)} holds NaN or infinite values")
    observation_space, action_space = _spaces(info.observation_dim, info.action_dim)
    kwargs = policy_kwargs(widths)
    if activation is not None:
        kwargs["activation_fn"] = activation
    policy = ActorCriticPolicy(observation_space, action_space, lambda _: 0.0, **kwargs).to(device)
    expected = policy.state_dict()
    for name, tensor in expected.items():
        if name not in state:
            raise AgentError(
                f"{where}: the weights do not fit the network: no tensor {name} (expected shape "
                f"{list(tensor.shape)})"
            )
        if state[name].shape != tensor.shape:
            raise AgentError(
                f"{where}: the weights do not fit the network: tensor {name} has shape "
                f"{list(state[name].shape)}, expected {list(tensor.shape)}"
            )
    extra = [name for name in state if name not in expected]
    if extra:
        raise AgentError(
            f"{where}: the weights do not fit the network: tensor {_tensor_name(extra[0])} is not one of "
            f"its {len(expected)} (PPO-{label}, {info.observation_dim} observations)"
        )
    try:
        policy.load_state_dict(state)
    except RuntimeError as error:  # after the checks above, a bug here rather than the file's
        raise AgentError(f"{where}: the weights do not fit the network: {_first_line(error)}") from None
    policy.set_training_mode(False)
    return policy, label


def _tensor_name(name: str) -> str:
    """A tensor's name from the file, for an error: a short dotted name as it is, anything else as
    an excerpt."""
    if re.fullmatch(r"[\w.]{1,80}", name, flags=re.ASCII):
        return name
    shown = json.dumps(name)
    return shown if len(shown) <= 24 else shown[:21] + "..."


def _torch_error(error: BaseException) -> str:
    """What went wrong in ``torch.load``, in a sentence: its weights-only unpickler's own finding
    (``Unsupported operand 103``) rather than the paragraph around it, which suggests loading the file
    unsafely."""
    text = str(error)
    if "WeightsUnpickler error:" in text:
        text = text.split("WeightsUnpickler error:", 1)[1]
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    first = lines[0].split(". ")[0].removesuffix(".") if lines else ""
    return f"{type(error).__name__}: {first[:160]}{'...' if len(first) > 160 else ''}"


def _weights(where: str, data: bytes, device: str) -> dict[str, Any]:
    """``policy.pth`` read by ``torch.load(weights_only=True)``: a state dict of dense floating-point
    tensors (AgentError naming the file, the member and the tensor otherwise)."""
    import warnings

    import torch

    try:
        with warnings.catch_warnings():
            # torch's notes on what it reads (sparse tensors, their beta state): such a tensor is
            # refused below in one line.
            warnings.simplefilter("ignore")
            state = torch.load(io.BytesIO(data), map_location=device, weights_only=True)
    except Exception as error:  # noqa: BLE001 - a corrupt policy.pth fails in torch in many ways
        raise AgentError(
            f"{where}: cannot load it with torch.load(weights_only=True): {_torch_error(error)}"
        ) from None
    if not isinstance(state, dict) or not all(
        isinstance(k, str) and isinstance(v, torch.Tensor) for k, v in state.items()
    ):
        raise AgentError(f"{where}: cannot load it as a policy: it holds no state dict (tensors by name)")
    for name, tensor in state.items():
        shown = _tensor_name(name)
        if tensor.layout != torch.strided:
            layout = str(tensor.layout).removeprefix("torch.")
            raise AgentError(f"{where}: tensor {shown} is a {layout} tensor; a policy's weights are dense")
        if tensor.device.type == "meta":
            raise AgentError(f"{where}: tensor {shown} holds no values (a meta tensor)")
        if not tensor.is_floating_point():
            dtype = str(tensor.dtype).removeprefix("torch.")
            raise AgentError(f"{where}: tensor {shown} holds {dtype} values, not floating-point weights")
    return state


def _activation(path: Path, kwargs: Any):
    """policy_kwargs' activation_fn as a torch.nn class (None: SB3's default, Tanh), and a check that
    the features extractor is one snakesim builds; read from the JSON that SB3 writes beside a
    pickled entry, never from the pickle."""
    import torch

    if not isinstance(kwargs, Mapping):
        return None
    extractor = kwargs.get("features_extractor_class")
    if extractor is not None and extractor not in _EXTRACTORS:
        raise AgentError(f"{path}: unsupported features extractor {str(extractor)[:80]}")
    name = kwargs.get("activation_fn")
    if name is None:
        return None
    match = re.fullmatch(r"<class 'torch\.nn\.modules\.activation\.(\w+)'>", str(name))
    if not match or match.group(1) not in _ACTIVATIONS:
        raise AgentError(f"{path}: unsupported activation_fn {str(name)[:80]}")
    return getattr(torch.nn, match.group(1))


def _widths(path: Path | str, state: Mapping[str, Any], info: ModelInfo) -> dict[str, list[int]]:
    """The widths of the shared trunk and the heads, read from the weights' shapes, checked layer by
    layer (each Linear takes what the one before gives) before anything is built from them."""
    widths: dict[str, list[int]] = {}
    trunk_out = info.observation_dim
    for part, prefix in _PARTS.items():
        sizes: list[int] = []
        width = info.observation_dim if part == "shared" else trunk_out
        while f"{prefix}.{2 * len(sizes)}.weight" in state:
            weight = state[f"{prefix}.{2 * len(sizes)}.weight"]
            if weight.dim() != 2 or weight.shape[1] != width:
                raise AgentError(
                    f"{path}: the weights do not fit the network: {prefix}.{2 * len(sizes)}.weight has "
                    f"shape {list(weight.shape)}, expected [*, {width}]"
                )
            width = int(weight.shape[0])
            sizes.append(width)
        widths[part] = sizes
        if part == "shared" and sizes:
            trunk_out = sizes[-1]
    # SB3 2.x registers a shared trunk under three names; they must be one set of weights.
    for key, value in state.items():
        owner, _, rest = key.partition(".")
        if owner in ("pi_features_extractor", "vf_features_extractor"):
            same = state.get(f"features_extractor.{rest}")
            if same is None or same.shape != value.shape or not bool((same == value).all()):
                raise AgentError(f"{path}: separate policy and value trunks are not supported")
    if not widths["pi"] or not widths["vf"]:
        raise AgentError(f"{path}: the weights do not fit the network: no policy and value layers")
    return widths


def _spaces(obs_dim: int, act_dim: int):
    from gymnasium import spaces

    return (
        spaces.Box(-np.inf, np.inf, (obs_dim,), dtype=np.float32),
        spaces.Box(-1.0, 1.0, (act_dim,), dtype=np.float32),
    )


# -- VecNormalize statistics ----------------------------------------------------------------------
def load_normalizer(path: str | os.PathLike, observation_size: int | None = None):
    """A ``VecNormalize`` saved beside a model, for evaluation (not updated); AgentError when the file
    is not one. Unpickled through an allow-list (:mod:`snakesim.agents.safe_pickle`): a pickle that
    names anything else is refused before it runs, and one that asks for statistics larger than
    ``observation_size`` (the model's; None: ``LIMITS['space_size']``) before they are allocated."""
    from stable_baselines3.common.vec_env import VecNormalize

    from snakesim.agents.safe_pickle import RefusedPickle, load_statistics

    name = os.fspath(path)
    try:
        normalizer = load_statistics(read_bytes(path, "config_bytes"), observation_size)
    except FileError as error:
        raise AgentError(str(error)) from None
    except RefusedPickle as error:
        raise AgentError(f"{name}: refused: {error}") from None
    except OSError as error:
        raise AgentError(f"cannot read {name}: {error.strerror or error}") from None
    except Exception as error:  # noqa: BLE001 - unpickling garbage fails in many ways
        raise AgentError(f"{name} is not a VecNormalize pickle: {_first_line(error)}") from None
    if not isinstance(normalizer, VecNormalize):
        raise AgentError(f"{name} is not a VecNormalize pickle (it holds {type(normalizer).__name__})")
    normalizer.training = False
    return normalizer


def _check_statistics(path: Path, normalizer: Any, obs_dim: int) -> None:
    """AgentError unless the statistics normalise the model's observations (finite, of its size) to
    finite values: ``(obs - mean) / sqrt(var + epsilon)`` clipped to ``clip_obs``."""
    rms = getattr(normalizer, "obs_rms", None)
    mean, var = getattr(rms, "mean", None), getattr(rms, "var", None)
    fits = all(
        isinstance(a, np.ndarray) and a.shape == (obs_dim,) and a.dtype.kind in "iuf" for a in (mean, var)
    )
    if not fits or not (np.isfinite(mean).all() and np.isfinite(var).all() and (var >= 0).all()):
        raise AgentError(f"{path}: not the statistics of {obs_dim} finite observations the model takes")

    def number(value: Any) -> bool:
        return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)

    epsilon, clip = getattr(normalizer, "epsilon", None), getattr(normalizer, "clip_obs", None)
    if not (number(epsilon) and math.isfinite(epsilon) and epsilon >= 0 and (var + epsilon > 0).all()):
        raise AgentError(f"{path}: its epsilon is not a number that keeps var + epsilon positive")
    if not (number(clip) and clip > 0):
        raise AgentError(f"{path}: its clip_obs is not a positive number")
    if not isinstance(getattr(normalizer, "norm_obs", None), (bool, np.bool_)):
        raise AgentError(f"{path}: its norm_obs is not true or false")


# -- baselines ------------------------------------------------------------------------------------
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

    files: tuple[str, ...] = ()
    if env_from is not None:
        if joints is not None or preset is not None:
            raise AgentError(f"--env-from takes joints and preset from {os.fspath(env_from)}: leave them out")
        if isinstance(env_from, str) and env_from.startswith(BASELINE_PREFIX):
            raise AgentError(f"--env-from needs a model or a run directory, not {env_from}")
        source = load_agent(env_from)
        # The agent's env without its assist: the baseline sets every action itself.
        env_kwargs: dict[str, Any] = {**source.env_kwargs, **(env_overrides or {})}
        files = source.files
    else:
        env_kwargs = {
            "task": task,
            "joints": GOAL_ENV_DEFAULTS["joints"] if joints is None else joints,
            "preset": GOAL_ENV_DEFAULTS["preset"] if preset is None else preset,
            **(env_overrides or {}),
        }
    try:
        controller = baselines.Controller(name, env_kwargs)
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
        files=files,
    )
