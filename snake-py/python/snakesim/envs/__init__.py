"""The environments: the paper's task and the goal task (:mod:`snakesim.envs.env`), their keywords
(:mod:`snakesim.envs.config`), Gymnasium's vector API and SB3's ``VecEnv`` over the batched Rust env
(:mod:`~snakesim.envs.vector`, :mod:`~snakesim.envs.sb3`), the Rerun wrapper and the top-down render."""

from __future__ import annotations

from snakesim.envs.env import SnakeEnv, SnakeGoalEnv, make_env
from snakesim.envs.vector import SnakeVectorEnv

__all__ = ["SnakeEnv", "SnakeGoalEnv", "SnakeVectorEnv", "make_env"]


def __getattr__(name: str):
    # Its modules on first use (``snakesim.envs.render`` after ``import snakesim``), none at import.
    import importlib
    import pkgutil

    if name in {module.name for module in pkgutil.iter_modules(__path__)}:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
