"""Loading agents: native models, run directories, SB3 2.x zips, the paper's SB3 1.x zips, baselines.

:func:`load_agent` finds out once what a path holds (:func:`snakesim.agents.locate.locate`) and hands
it to the class of agent that reads that format (:class:`~snakesim.agents.native.NativeAgent`,
:class:`~snakesim.agents.sb3.SB3Agent`), which reads each file once; ``baseline:NAME`` is a
:class:`~snakesim.agents.baseline_agent.BaselineAgent`. Every agent then answers through one
protocol (:class:`~snakesim.agents.protocol.Agent`). Loading never runs code from a file: a native
model is JSON and tensors parsed by Rust; of an SB3 zip only the JSON ``data`` (as plain data: no
pickled entry is unpickled) and ``policy.pth`` (``torch.load(weights_only=True)``) are read, and the
network is rebuilt from the shapes of its weights; VecNormalize statistics are unpickled through an
allow-list (:mod:`snakesim.agents.safe_pickle`). See docs/formats.md.

The names other modules and users import from here stay here (re-exported from the modules that
define them).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from snakesim.agents.baseline_agent import BASELINE_PREFIX, BaselineAgent, load_baseline
from snakesim.agents.locate import Located, locate, model_format, normalizer_beside
from snakesim.agents.native import NativeAgent
from snakesim.agents.protocol import Agent, AgentError, Keyword
from snakesim.agents.recorded import bind_assist
from snakesim.agents.sb3 import SB3Agent, load_normalizer
from snakesim.agents.sb3_zip import (
    EXPORTED_ASSIST_KEY,
    EXPORTED_ENV_KEY,
    RECORDED_FILES_KEY,
    ModelInfo,
    inspect_model,
    recorded_env_files,
    safe_custom_objects,
)

__all__ = [
    "BASELINE_PREFIX",
    "EXPORTED_ASSIST_KEY",
    "EXPORTED_ENV_KEY",
    "RECORDED_FILES_KEY",
    "Agent",
    "AgentError",
    "BaselineAgent",
    "Located",
    "ModelInfo",
    "NativeAgent",
    "SB3Agent",
    "bind_assist",
    "env_kwargs_of",
    "inspect_model",
    "load_agent",
    "load_normalizer",
    "model_format",
    "normalizer_beside",
    "recorded_env_files",
    "safe_custom_objects",
]


def load_agent(
    source: str | os.PathLike,
    *,
    joints: int | None = None,
    preset: str | None = None,
    env_overrides: Mapping[str, Any] | None = None,
    device: str = "cpu",
    task: str = "goal",
    env_from: str | os.PathLike | None = None,
    hold: tuple[float, float] | None = None,
) -> Agent:
    """A run directory (its final model, else its latest checkpoint; its config.yaml), a bare SB3 zip
    (with the statistics beside it, see :func:`normalizer_beside`) or a native ``.safetensors`` model.

    For a run directory, ``joints`` and ``preset`` must agree with its config when given. For a bare
    zip, ``joints`` defaults to what the model's action space says and ``preset`` to ``paper``; a
    native model file names its own env. A baseline (``baseline:NAME``) runs in ``task``'s env
    (``goal``, ``pegs``, ``rough``), or with ``env_from`` (a model or run directory) in exactly the env
    recorded there; ``hold`` sets a gait-action baseline's amplitude and frequency actions (each in
    [-1, 1]; the baselines hold 0, the middle of their ranges).

    An :class:`AgentError` about these arguments names them as they are named here (``env_from``);
    ``error.naming({"env_from": "--env-from"})`` names them as a command does.
    """
    if isinstance(source, str) and source.startswith(BASELINE_PREFIX):
        name = source.removeprefix(BASELINE_PREFIX)
        if env_from is None:
            return load_baseline(name, joints, preset, env_overrides, task=task, hold=hold)
        if joints is not None or preset is not None:
            raise AgentError(
                Keyword("env_from"), f" takes joints and preset from {os.fspath(env_from)}: leave them out"
            )
        return load_baseline(name, None, None, env_overrides, source=_env_source(env_from), hold=hold)
    if hold is not None:
        from snakesim.agents.baselines import GAIT_NAMES

        gait = ", ".join(BASELINE_PREFIX + n for n in GAIT_NAMES)
        raise AgentError(Keyword("hold"), f" is for the gait-action baselines ({gait})")
    if task != "goal" or env_from is not None:
        raise AgentError(
            Keyword("task"),
            " and ",
            Keyword("env_from"),
            " are for baselines: a model evaluates on the env it was trained on",
        )
    located = locate(Path(source))
    return located.reader.read(located, joints=joints, preset=preset, overrides=env_overrides, device=device)


def _env_source(source: str | os.PathLike) -> Agent:
    """The agent whose env a baseline runs in (``env_from``); a baseline has no recorded env."""
    # The message names the command's flag: snake-py/tests/test_tasks.py matches it on this function.
    if isinstance(source, str) and source.startswith(BASELINE_PREFIX):
        raise AgentError(f"--env-from needs a model or a run directory, not {source}")
    return load_agent(source)


def env_kwargs_of(source: str | os.PathLike) -> dict[str, Any]:
    """The env keywords recorded in a model's metadata or a run directory (what :func:`load_agent`
    would evaluate the agent on), for running a baseline on exactly that env."""
    return dict(_env_source(source).env_kwargs)
