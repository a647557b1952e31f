"""snakesim: the "Simulating Snakes" robot on Bullet, bit for bit as pybullet 3.2.7 moves it.

- :class:`SnakeEnv`, a :class:`gymnasium.Env`, registered as ``snakesim/Snake-v0``::

      import gymnasium, snakesim
      env = gymnasium.make("snakesim/Snake-v0", joints=5, preset="snakebot-gym")

- :class:`SnakeVecEnv`, Stable-Baselines3's ``VecEnv`` over the batched Rust env (threads, no
  subprocesses), and :class:`SnakeVectorEnv`, the same for Gymnasium's vector API.
"""

from __future__ import annotations

import gymnasium

from snakesim._core import __version__
from snakesim.config import ENV_DEFAULTS
from snakesim.env import SnakeEnv
from snakesim.vector import SnakeVectorEnv

__all__ = ["SnakeEnv", "SnakeVecEnv", "SnakeVectorEnv", "__version__", "register_envs"]

ENV_ID = "snakesim/Snake-v0"


def register_envs() -> None:
    """Registers ``snakesim/Snake-v0`` with Gymnasium (done on import)."""
    if ENV_ID not in gymnasium.registry:
        # The env truncates at its own max_episode_steps; the spec's 5000 (Snake-v0's) tells tools the
        # episode length, and gymnasium.make(..., max_episode_steps=T) adds a TimeLimit of T.
        steps = ENV_DEFAULTS["max_episode_steps"]
        gymnasium.register(id=ENV_ID, entry_point="snakesim.env:SnakeEnv", max_episode_steps=steps)


def __getattr__(name: str):
    # SnakeVecEnv needs stable-baselines3, an optional dependency: import it only when asked for.
    if name == "SnakeVecEnv":
        from snakesim.sb3 import SnakeVecEnv

        return SnakeVecEnv
    raise AttributeError(f"module 'snakesim' has no attribute {name!r}")


register_envs()
