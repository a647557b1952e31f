"""What a training session ends with, shared by both trainers: its result, or why it stopped."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any


class TrainingFailed(RuntimeError):
    """Training stopped on an error of the run itself (a loss or gradient became non-finite, an env
    blew up); the message says where, and what was saved."""


class TrainingInterrupted(Exception):
    """Ctrl-C during training; a checkpoint was saved at ``timesteps`` in ``path``."""

    def __init__(self, timesteps: int, path: Path) -> None:
        super().__init__(f"interrupted at {timesteps} timesteps; saved {path}")
        self.timesteps = timesteps
        self.path = path


@dataclasses.dataclass
class TrainResult:
    run_dir: Path
    start_timesteps: int
    timesteps: int
    seconds: float  # wall time of this session's training, evaluations included
    eval_seconds: float
    last_evaluation: dict[str, Any] | None
    details: dict[str, Any] | None = None  # the native trainer's split of the time, threads, memory

    @property
    def timesteps_per_second(self) -> float:
        return (self.timesteps - self.start_timesteps) / self.seconds if self.seconds > 0 else 0.0

    @property
    def training_timesteps_per_second(self) -> float:
        busy = self.seconds - self.eval_seconds
        return (self.timesteps - self.start_timesteps) / busy if busy > 0 else 0.0


def format_eval(evaluation: Mapping[str, Any]) -> str:
    return f"eval R {evaluation['mean_return']:.0f}, success {evaluation['success_rate']:.0%}"
