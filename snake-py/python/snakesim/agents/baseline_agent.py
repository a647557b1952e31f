"""Hand-made controllers as agents (``baseline:NAME``, :mod:`snakesim.agents.baselines`): in a task's
env, or in exactly the env an agent was trained in."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from snakesim.agents.protocol import Agent, AgentError, Keyword

#: ``baseline:NAME`` names a hand-made controller (snakesim.agents.baselines).
BASELINE_PREFIX = "baseline:"


@dataclasses.dataclass
class BaselineAgent(Agent):
    """A hand-made controller; ``policy`` is a :class:`snakesim.agents.baselines.Controller`. Its
    actions are its own, with no ``steer_assist``; it is no network, so it exports to nothing."""

    kind: ClassVar[str] = "baseline"
    trainer: ClassVar[str] = "hand-made controller"

    @property
    def network(self) -> str:
        return "baseline"

    @property
    def label(self) -> str:
        return self.path

    def act(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        return self.policy.act(obs)

    def own_actions(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        return self.policy.act(obs)

    def restart(self, env: int | None = None) -> None:
        """A baseline with a clock (``baseline:sine``) restarts it."""
        restart = getattr(self.policy, "restart", None)
        if restart is not None:
            restart(env)

    def actor(self) -> Any:
        from snakesim.runs.onnx import ExportError

        raise ExportError(f"{self.path} is a hand-made controller, not a model: export takes runs and models")


def load_baseline(
    name: str,
    joints: int | None,
    preset: str | None,
    env_overrides: Mapping[str, Any] | None,
    *,
    task: str = "goal",
    source: Agent | None = None,
    hold: tuple[float, float] | None = None,
) -> BaselineAgent:
    """The baseline ``name`` in ``task``'s env (the goal task, ``snakesim/SnakeGoal-v0``, unless told)
    with ``joints`` (5) and ``preset`` (paper), or with ``source`` (an agent) in exactly the env it
    was trained in, without its assist: the baseline sets every action itself. ``hold``: a gait-action
    baseline's amplitude and frequency actions (see :class:`snakesim.agents.baselines.Controller`);
    its path then reads ``baseline:NAME --hold A,F``."""
    from snakesim.agents import baselines
    from snakesim.envs.config import GOAL_ENV_DEFAULTS

    files: tuple[str, ...] = ()
    if source is not None:
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
        controller = baselines.Controller(name, env_kwargs, hold)
    except (TypeError, ValueError) as error:
        message = str(error)
        if message.startswith("hold: "):
            raise AgentError(Keyword("hold"), message.removeprefix("hold")) from None
        raise AgentError(message) from None
    held = "" if hold is None else f" --hold {hold[0]:g},{hold[1]:g}"
    return BaselineAgent(
        policy=controller,
        path=BASELINE_PREFIX + name + held,
        env_kwargs=env_kwargs,
        arch="baseline",
        sb3_version="-",
        num_timesteps=None,
        files=files,
    )
