"""Trained agents and hand controllers: loading them (:mod:`~snakesim.agents.loading`), the
evaluation protocol (:mod:`~snakesim.agents.evaluation`) and the baselines
(:mod:`~snakesim.agents.baselines`)."""

from __future__ import annotations

from snakesim.agents.evaluation import evaluate, run_episodes
from snakesim.agents.loading import Agent, AgentError, inspect_model, load_agent

__all__ = ["Agent", "AgentError", "evaluate", "inspect_model", "load_agent", "run_episodes"]
