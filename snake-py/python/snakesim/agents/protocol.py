"""What every agent offers, whatever format it was read from: the :class:`Agent` protocol.

An agent is a policy plus what it needs to act in snakesim: the env keywords it was trained with, the
files it was read from and, when it was trained with one, ``baseline:steer``'s share of its actions
(``steer_assist``). Each model format is one subclass (:class:`snakesim.agents.native.NativeAgent`,
:class:`snakesim.agents.sb3.SB3Agent`, :class:`snakesim.agents.baseline_agent.BaselineAgent`), and
what differs between formats is a method of it, never a branch on a name:

- ``own_actions`` (and so ``act``): the policy's actions for a batch of observations;
- ``observation_structure``: the parts of the observation it acts on, in order;
- ``normalization``: the observation statistics the policy applies before its network, or None;
- ``actor``: the policy as numbers for an ONNX graph (:mod:`snakesim.runs.onnx`), or an
  ``ExportError`` saying why it has none; ``exports_sb3``: whether ``snakesim export --sb3``
  (:func:`snakesim.runs.export.to_sb3`) writes it as a Stable-Baselines3 zip.
"""

from __future__ import annotations

import dataclasses
from typing import Any, ClassVar

import numpy as np

from snakesim.runs.arguments import ArgumentError, Keyword

__all__ = ["Agent", "AgentError", "Keyword", "first_line"]


class AgentError(ArgumentError):
    """A model or run directory that cannot be used; the message says why. A message about the
    loader's own arguments names them by their Python names (``env_from``); :meth:`naming` gives it
    with the names a caller uses for them (a command's flags, ``--env-from``)."""


def first_line(error: BaseException, limit: int = 160) -> str:
    """The error's type and the start of its first line, for a one-line message."""
    lines = str(error).strip().splitlines()
    first = lines[0] if lines else ""
    return f"{type(error).__name__}: {first[:limit]}{'...' if len(first) > limit else ''}"


@dataclasses.dataclass
class Agent:
    """An agent of any format; see the module's docstring. Subclasses set ``kind`` (a label for
    people and tests, never dispatched on) and implement :meth:`own_actions`."""

    policy: Any
    path: str  # the model file (for a baseline, ``baseline:NAME``)
    env_kwargs: dict[str, Any]  # joints, preset and the rest of the env's keywords
    arch: str
    sb3_version: str
    num_timesteps: int | None
    config: dict[str, Any] | None = None  # the run's config.yaml, when loaded from a run directory
    # The files it was read from (model, config.yaml, statistics): what a command must not overwrite.
    files: tuple[str, ...] = ()
    # baseline:steer's share of its actions (a _core.SteerAssist), when it was trained with one:
    # applied in act, so whatever steps the env with act's actions runs the agent as it was trained.
    steer_assist: Any = None

    #: "native", "sb3" or "baseline": what it is, in a word.
    kind: ClassVar[str] = ""
    #: Who made the policy, in words (``evaluate``'s report).
    trainer: ClassVar[str] = ""
    #: Whether :func:`snakesim.runs.export.to_sb3` writes it (native models: an SB3 model already is one).
    exports_sb3: ClassVar[bool] = False

    @property
    def joints(self) -> int:
        """The driven joints: the snake's, or a robot's movable joints (whatever ``joints`` says)."""
        if self.env_kwargs.get("robot"):
            from snakesim import _core
            from snakesim.envs.config import env_config

            return int(_core.Env(env_config(**self.env_kwargs)).joints)
        return int(self.env_kwargs["joints"])

    @property
    def network(self) -> str:
        """The policy's network in a word: ``PPO-small``."""
        return f"PPO-{self.arch}"

    @property
    def label(self) -> str:
        """What acts, in words: ``PPO-small`` or ``baseline:steer``."""
        return self.network

    @property
    def body(self) -> str:
        """The body it drives, in words: ``10 joints`` or ``robot robots/yaw-pitch-16.yaml (15 joints)``."""
        from snakesim.envs.config import file_label

        robot = self.env_kwargs.get("robot")
        return f"{self.joints} joints" if not robot else f"robot {file_label(robot)} ({self.joints} joints)"

    @property
    def observation_structure(self) -> dict[str, Any]:
        """The observation it acts on, part by part in order: its env's ``observation_structure``."""
        from snakesim.envs.env import make_env

        return make_env(**self.env_kwargs).observation_structure

    def act(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        """The env's actions for a batch of observations: the policy's own, or with a
        ``steer_assist``, its composition of them (float64)."""
        actions = self.own_actions(obs, deterministic)
        if self.steer_assist is None:
            return actions
        obs = np.ascontiguousarray(np.atleast_2d(obs), dtype=np.float32)
        return self.steer_assist.apply(obs, np.atleast_2d(actions))

    def own_actions(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        """The policy's own actions (before any ``steer_assist``), in [-1, 1]."""
        raise NotImplementedError

    def restart(self, env: int | None = None) -> None:
        """Row ``env`` of the batch starts a new episode (every row, with None); policies have no
        state between steps, a baseline with a clock restarts it."""

    def normalization(self) -> Any:
        """The observation statistics its policy applies before the network, as a
        :class:`snakesim.runs.onnx.Normalization`, or None when it takes raw observations."""
        return None

    def actor(self) -> Any:
        """Its deterministic action as numbers (:class:`snakesim.runs.onnx.Actor`), what an ONNX graph
        is built from; ExportError when it has none."""
        from snakesim.runs.onnx import ExportError

        raise ExportError(f"{self.path} is not a model that an ONNX graph can hold")
