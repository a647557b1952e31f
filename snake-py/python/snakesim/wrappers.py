"""Gymnasium wrappers of the snakesim envs (the public name of :mod:`snakesim.envs.wrappers`)."""

from __future__ import annotations

from snakesim.envs.wrappers import RerunLogger, SteerAssist

__all__ = ["RerunLogger", "SteerAssist"]
