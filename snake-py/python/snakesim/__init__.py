"""snakesim: the "Simulating Snakes" robot on Bullet, bit for bit as pybullet 3.2.7 moves it.

- :class:`SnakeEnv`, a :class:`gymnasium.Env`, registered as ``snakesim/Snake-v0``::

      import gymnasium, snakesim
      env = gymnasium.make("snakesim/Snake-v0", joints=5, preset="snakebot-gym")

- :class:`SnakeGoalEnv`, goals in any direction 5-15 m away, steered through a gait, registered as
  ``snakesim/SnakeGoal-v0``::

      env = gymnasium.make("snakesim/SnakeGoal-v0", joints=10)

- :class:`SnakeVecEnv`, Stable-Baselines3's ``VecEnv`` over the batched Rust env (threads, no
  subprocesses), and :class:`SnakeVectorEnv`, the same for Gymnasium's vector API.

- :class:`snakesim.wrappers.RerunLogger`, a wrapper that logs episodes to Rerun as they run (the cubes
  in 3D at every physics step, the joints, the reward); :mod:`snakesim.viewer.recording` says
  what a recording holds.

The package by concern: :mod:`snakesim.envs`, :mod:`snakesim.runs`, :mod:`snakesim.agents`,
:mod:`snakesim.sweeps`, :mod:`snakesim.viewer`, :mod:`snakesim.cli`. Each, and each of their modules,
is an attribute after ``import snakesim`` alone, imported on first use (``import snakesim`` imports
none of the optional packages: torch, Ray, onnx, rerun)::

    snakesim.runs.onnx.to_onnx(snakesim.agents.load_agent("models/paper-10.safetensors"))
"""

from __future__ import annotations

import gymnasium

from snakesim import extras
from snakesim._core import __version__
from snakesim.envs.config import (
    ENV_DEFAULTS,
    GOAL_ENV_DEFAULTS,
    PEGS_ENV_DEFAULTS,
    ROUGH_ENV_DEFAULTS,
    SWIM_ENV_DEFAULTS,
)
from snakesim.envs.env import SnakeEnv, SnakeGoalEnv, SnakePegsEnv, SnakeRoughEnv, SnakeSwimEnv
from snakesim.envs.vector import SnakeVectorEnv

__all__ = [
    "SnakeEnv",
    "SnakeGoalEnv",
    "SnakePegsEnv",
    "SnakeRoughEnv",
    "SnakeSwimEnv",
    "SnakeVectorEnv",
    "__version__",
    "register_envs",
]
if extras.available("sb3"):  # without the extra, `from snakesim import *` leaves it out
    __all__.insert(2, "SnakeVecEnv")

ENV_ID = "snakesim/Snake-v0"
GOAL_ENV_ID = "snakesim/SnakeGoal-v0"
PEGS_ENV_ID = "snakesim/SnakePegs-v0"
ROUGH_ENV_ID = "snakesim/SnakeRough-v0"
SWIM_ENV_ID = "snakesim/SnakeSwim-v0"


def register_envs() -> None:
    """Registers ``snakesim/Snake-v0``, ``snakesim/SnakeGoal-v0``, ``snakesim/SnakePegs-v0``,
    ``snakesim/SnakeRough-v0`` and ``snakesim/SnakeSwim-v0`` with Gymnasium (done on import);
    ``gymnasium.make_vec`` of each gives the native :class:`SnakeVectorEnv` (Rust threads), with
    ``gymnasium.make``'s keywords."""
    # gymnasium.make wraps the env in a TimeLimit of the spec's max_episode_steps (the task's default),
    # or of T with gymnasium.make(..., max_episode_steps=T). That wrapper alone truncates: the env is
    # made with max_episode_steps=None (no limit of its own), so that T may also exceed the default.
    for env_id, env_class, defaults in (
        (ENV_ID, SnakeEnv, ENV_DEFAULTS),
        (GOAL_ENV_ID, SnakeGoalEnv, GOAL_ENV_DEFAULTS),
        (PEGS_ENV_ID, SnakePegsEnv, PEGS_ENV_DEFAULTS),
        (ROUGH_ENV_ID, SnakeRoughEnv, ROUGH_ENV_DEFAULTS),
        (SWIM_ENV_ID, SnakeSwimEnv, SWIM_ENV_DEFAULTS),
    ):
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point=f"snakesim.envs.env:{env_class.__name__}",
                vector_entry_point=f"snakesim.envs.vector:{env_class.task}_vector_env",
                max_episode_steps=defaults["max_episode_steps"],
                kwargs={"max_episode_steps": None},
            )


#: The subpackages and modules reachable as attributes of ``snakesim`` (``snakesim.runs.onnx``), each
#: imported when first asked for, so that ``import snakesim`` stays quick and needs no extra.
_SUBMODULES = ("agents", "cli", "envs", "extras", "files", "limits", "runs", "sweeps", "viewer", "wrappers")


def __getattr__(name: str):
    # SnakeVecEnv needs stable-baselines3 (the extra snakesim[sb3]): import it only when asked for; without
    # it, asking is an ImportError naming the pip install (snakesim.extras).
    if name == "SnakeVecEnv":
        from snakesim.envs.sb3 import SnakeVecEnv

        return SnakeVecEnv
    if name in _SUBMODULES:
        import importlib

        return importlib.import_module(f"snakesim.{name}")
    raise AttributeError(f"module 'snakesim' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_SUBMODULES})


register_envs()
