"""Stable-Baselines3 models (a bare zip, 2.x or the paper's 1.x, or an SB3 run's): the zip read as
data (:mod:`snakesim.agents.sb3_zip`), the network rebuilt from its weights
(:mod:`snakesim.agents.sb3_network`), the VecNormalize statistics beside it unpickled through an
allow-list (:mod:`snakesim.agents.safe_pickle`). The policy acts through SB3's own ``predict``."""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from snakesim import extras
from snakesim.agents.protocol import Agent, AgentError, Keyword, first_line
from snakesim.agents.recorded import agreed_env, bind_assist, check_env, note
from snakesim.agents.sb3_network import sb3_policy
from snakesim.agents.sb3_zip import EXPORTED_ASSIST_KEY, EXPORTED_ENV_KEY, RECORDED_FILES_KEY, read_zip
from snakesim.envs.config import ENV_DEFAULTS
from snakesim.files import FileError, read_bytes
from snakesim.runs import config as runconfig

if TYPE_CHECKING:  # pragma: no cover - names for annotations only
    from snakesim.runs.onnx import Actor, Normalization


@dataclasses.dataclass
class SB3Agent(Agent):
    """An SB3 model; ``policy`` is an SB3 ``ActorCriticPolicy`` (snakesim's networks)."""

    obs_normalizer: Any = None  # a VecNormalize whose statistics normalise observations, or None

    kind: ClassVar[str] = "sb3"

    @property
    def trainer(self) -> str:  # type: ignore[override]
        return f"SB3 {self.sb3_version}"

    @classmethod
    def read(
        cls,
        located: Any,
        *,
        joints: int | None,
        preset: str | None,
        overrides: Mapping[str, Any] | None,
        device: str = "cpu",
    ) -> SB3Agent:
        """The zip of ``located`` (a :class:`snakesim.agents.locate.Located`), bare or a run's, with
        its statistics when it has them."""
        model: Path = located.model
        archive = read_zip(model)
        info = archive.info
        hint: tuple[str | Keyword, ...] = ()
        recorded = archive.data.get(EXPORTED_ENV_KEY)
        if located.config is not None:
            recorded = runconfig.env_kwargs(located.config)
            env_kwargs = agreed_env(model.parent, recorded, joints, preset, None)
        elif isinstance(recorded, dict) and ":serialized:" not in recorded:  # by snakesim export
            env_kwargs = agreed_env(model, dict(recorded), joints, preset, None)
        else:
            bare_joints = info.action_dim if joints is None else joints
            env_kwargs = {
                "joints": bare_joints,
                "preset": preset or ENV_DEFAULTS["preset"],
                **(overrides or {}),
            }
            hint = (
                ": pass ",
                Keyword("joints"),
                f" {info.action_dim} (or the observation it was trained with)",
            )
        if not hint:
            # The recorded robot and world files, where the env keywords are known (not guessed); then
            # the caller's overrides (a robot file given in place of the recorded one runs as given).
            env_kwargs = _recorded_files(model, env_kwargs, archive.data.get(RECORDED_FILES_KEY), overrides)
            env_kwargs = {**env_kwargs, **(overrides or {})}
        check_env(model, env_kwargs, info.observation_dim, info.action_dim, hint)
        extras.require("sb3", f"loading the Stable-Baselines3 model {model}")
        policy, arch = sb3_policy(model, archive, device)
        normalizer = None
        if located.normalizer is not None:
            normalizer = load_normalizer(located.normalizer, info.observation_dim)
            _check_statistics(located.normalizer, normalizer, info.observation_dim)
        return cls(
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

    def own_actions(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        if self.obs_normalizer is not None:
            obs = self.obs_normalizer.normalize_obs(obs)
        actions, _ = self.policy.predict(obs, deterministic=deterministic)
        return actions

    def normalization(self) -> Normalization | None:
        """The VecNormalize's statistics, epsilon and clip, when it normalises observations."""
        from snakesim.runs.onnx import Normalization

        normalizer = self.obs_normalizer
        if normalizer is None or not getattr(normalizer, "norm_obs", True):
            return None
        rms = normalizer.obs_rms
        return Normalization(
            np.asarray(rms.mean, np.float64),
            np.asarray(rms.var, np.float64),
            float(normalizer.epsilon),
            float(normalizer.clip_obs),
        )

    def actor(self) -> Actor:
        from snakesim.runs.onnx import sb3_actor

        return sb3_actor(self.policy, self.normalization())


def _recorded_files(
    model: Path, env_kwargs: dict[str, Any], records: Any, overrides: Mapping[str, Any] | None = None
) -> dict[str, Any]:
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
    note([f"{model}: {line}" for line in notes], overrides)
    return env_kwargs


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
        raise AgentError(f"{name} is not a VecNormalize pickle: {first_line(error)}") from None
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
