"""Trained agents and hand controllers: loading them (:mod:`~snakesim.agents.loading`), the
evaluation protocol (:mod:`~snakesim.agents.evaluation`) and the baselines
(:mod:`~snakesim.agents.baselines`)."""

from __future__ import annotations

from snakesim.agents.evaluation import evaluate, run_episodes
from snakesim.agents.loading import Agent, AgentError, inspect_model, load_agent

__all__ = ["Agent", "AgentError", "evaluate", "inspect_model", "load_agent", "run_episodes"]


def __getattr__(name: str):
    # Its modules on first use (``snakesim.agents.baselines`` after ``import snakesim``), none at import.
    import importlib
    import pkgutil

    if name in {module.name for module in pkgutil.iter_modules(__path__)}:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
