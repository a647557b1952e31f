"""Gymnasium wrappers of the snakesim envs (imported by users as :mod:`snakesim.wrappers`)."""

from __future__ import annotations

import json
from typing import Any

import gymnasium
import numpy as np

from snakesim.envs.env import SnakeEnv
from snakesim.viewer.recording import MAX_SECONDS, RecordingError, SnakeLog, Trace, _rerun


def _robot_shapes(env: SnakeEnv) -> list | None:
    """The shapes of each link of the env's robot, or None for the built-in snake."""
    shapes = env._env.robot_shapes()
    return None if shapes is None else json.loads(shapes)


class RerunLogger(gymnasium.Wrapper):
    """Logs every episode of a snakesim env to Rerun as it runs: the cubes in 3D after every physics
    step, the goal, the head's path, the joints' angles, targets, velocities and torques, each reward
    term and the distance to the goal (see :mod:`snakesim.viewer.recording` for the entities and timelines).

    ``recording`` is a ``rerun.RecordingStream``; by default Rerun's current one, so::

        import gymnasium, rerun as rr, snakesim
        from snakesim.envs.wrappers import RerunLogger

        rr.init("snakesim", spawn=True)  # or rr.save("run.rrd"), rr.serve_grpc(), ...
        env = RerunLogger(gymnasium.make("snakesim/SnakeGoal-v0", joints=10))
        obs, info = env.reset(seed=0)

    Episodes follow one another on the recording's timelines. Rows are sent every ``flush_seconds`` of
    simulated time and at each episode's end. After ``max_seconds`` of simulated time in all (at most
    ``LIMITS["recording_seconds"]``) logging stops with a warning; the env runs on. Stepping is
    unchanged: the wrapped env gives the same observations and rewards, bit for bit.
    """

    def __init__(
        self,
        env: gymnasium.Env,
        recording: Any = None,
        *,
        flush_seconds: float = 1.0,
        max_seconds: float = MAX_SECONDS,
    ) -> None:
        super().__init__(env)
        base = env.unwrapped
        if not isinstance(base, SnakeEnv):
            raise TypeError(f"RerunLogger wraps a snakesim env, got {type(base).__name__}")
        if not (0 < max_seconds <= MAX_SECONDS):
            raise ValueError(f"max_seconds must be in (0, {MAX_SECONDS:g}], got {max_seconds}")
        if not flush_seconds > 0:
            raise ValueError(f"flush_seconds must be positive, got {flush_seconds}")
        rr = _rerun()
        if recording is None:
            recording = rr.get_data_recording()
        if recording is None:
            raise ValueError(
                "no Rerun recording: call rerun.init('snakesim', spawn=True) (or rerun.save(...)) first, "
                "or pass recording="
            )
        self.recording = recording
        self._base = base
        config = base.config
        self._dt = float(config["snake"]["dt"])
        self._goal_radius = float(config["goal_radius"])
        base.set_physics_trace(True)
        self.log = SnakeLog(
            recording,
            joints=base.joints,
            dt=self._dt,
            half_extent=base.half_extent,
            config=config,
            rewards=True,
            max_seconds=max_seconds,
            flush_rows=max(1, round(flush_seconds / self._dt)),
            shapes=_robot_shapes(base),
        )
        self._stopped = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        if not self._stopped:
            start = info["start"]
            goal = info["goal"]
            self.log.start_episode(
                goal=goal,
                goal_radius=self._goal_radius,
                note=f"episode {self.log.episodes + 1}: {'no seed' if seed is None else f'seed {seed}'}, "
                f"start ({start[0]:.2f}, {start[1]:.2f}) "
                f"yaw {start[3]:.2f}, goal ({goal[0]:.2f}, {goal[1]:.2f})",
            )
            self._log_trace()
        return obs, info

    def step(self, action: Any):
        obs, reward, terminated, truncated, info = self.env.step(action)
        if not self._stopped:
            step = self._log_trace()
            if step is not None:
                self.log.add_env_step(step, reward, info)
            if terminated or truncated:
                self.log.flush()
        return obs, reward, terminated, truncated, info

    def _log_trace(self) -> int | None:
        """Logs the physics steps of the latest reset or step; returns the last one's number."""
        raw = self._base.physics_trace()
        if raw is None:
            return None
        trace = Trace.from_core(raw)
        try:
            self.log.add_physics(trace)
        except RecordingError as error:
            self._stopped = True
            self.log.flush()
            gymnasium.logger.warn(f"RerunLogger stopped logging: {error}")
            return None
        return int(trace.steps[-1]) if len(trace) else None

    def close(self) -> None:
        self.log.flush()
        super().close()


class SteerAssist(gymnasium.Wrapper):
    """``baseline:steer`` sharing the agent's gait actions (snake-core's ``SteerAssist``, the same
    code the native trainer's ``steer_assist`` runs): with ``residual``, the agent's steering action
    corrects steer's, ``clip(steer + 2 a, -1, 1)``, so actions of 0 drive exactly ``baseline:steer``;
    within ``near_goal`` metres of the goal (0: off, at most 10) steer drives whatever the agent
    asks (a hand-over for the last approach). The action and observation spaces are the env's; the
    env is given the composed actions (float64), computed from the observation the action answers::

        env = SteerAssist(gymnasium.make("snakesim/SnakeRough-v0", joints=10), near_goal=2.5)

    The env needs gait actions and the goal vector (observation ``extended`` or ``terrain``).
    """

    def __init__(self, env: gymnasium.Env, *, residual: bool = False, near_goal: float = 0.0) -> None:
        from snakesim import _core

        super().__init__(env)
        base = env.unwrapped
        if not isinstance(base, SnakeEnv):
            raise TypeError(f"SteerAssist wraps a snakesim env, got {type(base).__name__}")
        if not isinstance(residual, bool):
            raise TypeError(f"residual must be True or False, got {residual!r}")
        self.assist = _core.SteerAssist(base._config_json, residual=residual, near_goal=near_goal)
        self._obs: np.ndarray | None = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        self._obs = obs
        return obs, info

    def step(self, action: Any):
        if self._obs is None:
            raise gymnasium.error.ResetNeeded("call reset() before step()")
        agent = np.asarray(action, dtype=np.float64).reshape(1, -1)
        composed = self.assist.apply(self._obs.reshape(1, -1), agent)[0]
        obs, reward, terminated, truncated, info = self.env.step(composed)
        self._obs = obs
        return obs, reward, terminated, truncated, info
