"""The native trainer (snake-rl, Rust) from Python: ``snakesim train`` with ``trainer: native``.

The whole training loop runs in Rust; Python only shows progress and turns Ctrl-C into a saved
checkpoint. The run directory has the layout of every snakesim run (see :mod:`snakesim.runs.rundir`), with
``model.safetensors`` and ``checkpoints/model_<T>_steps.safetensors`` for the policy.
"""

from __future__ import annotations

import json
import platform
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from snakesim import _core
from snakesim.runs import config as runconfig
from snakesim.runs.results import TrainingFailed, TrainingInterrupted, TrainResult
from snakesim.runs.rundir import RunDirError, default_run_dir, lock_run_dir


class _Progress:
    """Receives the Rust trainer's events: a tqdm bar of timesteps with timesteps/s and the latest
    evaluation, or one line per evaluation without a bar."""

    def __init__(
        self,
        show: bool,
        log: Callable[[str], None],
        on_evaluation: Callable[[dict[str, Any]], None] | None = None,
    ) -> None:
        self.show = show
        self.log = log
        self.on_evaluation_hook = on_evaluation
        self.bar = None
        self.last_evaluation: dict[str, Any] | None = None
        self.rate = 0.0

    def on_start(self, start: int, total: int) -> None:
        if self.show:
            from tqdm import tqdm

            self.bar = tqdm(
                total=total, initial=start, unit="step", unit_scale=True, dynamic_ncols=True, file=sys.stderr
            )
            self.bar.set_description("train")

    def on_step(self, timesteps: int) -> None:
        if self.bar is not None:
            self.bar.update(timesteps - self.bar.n)

    def _postfix(self) -> str:
        parts = [f"{self.rate:,.0f} steps/s"] if self.rate else []
        e = self.last_evaluation
        if e is not None:
            parts.append(f"eval R {e['mean_return']:.0f}, success {e['success_rate']:.0%}")
        return ", ".join(parts)

    def on_update(self, progress: Mapping[str, Any]) -> None:
        self.rate = progress["timesteps_per_second"]
        if self.bar is not None:
            self.bar.update(progress["timesteps"] - self.bar.n)
            self.bar.set_postfix_str(self._postfix())

    def on_note(self, message: str) -> None:
        if self.bar is not None:
            self.bar.write(f"note: {message}", file=sys.stderr)
        else:
            self.log(f"note: {message}")

    def on_evaluation(self, row: Mapping[str, Any]) -> None:
        self.last_evaluation = dict(row)
        if self.bar is not None:
            self.bar.set_postfix_str(self._postfix())
        else:
            self.log(f"{row['timesteps']} timesteps: {self._postfix()}")
        if self.on_evaluation_hook is not None:
            self.on_evaluation_hook(dict(row))

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


class NativeTrainer:
    """One training session of a native run: a new run, or ``resume=True`` to continue a run
    directory. ``overrides`` are configuration keys over the defaults, or over the run's saved
    config.yaml when resuming (the Rust side refuses changes to what is learnt). ``on_evaluation``
    is called with each evaluation row as it is written (an exception it raises stops training).

    The run directory is locked from here to the end of :meth:`run` (one writer per run directory): a
    second trainer on it raises RunDirError at once, naming the process that writes it."""

    def __init__(
        self,
        overrides: Mapping[str, Any],
        run_dir: str | Path | None = None,
        *,
        resume: bool = False,
        progress: bool | None = None,
        log: Callable[[str], None] | None = None,
        on_evaluation: Callable[[dict[str, Any]], None] | None = None,
    ) -> None:
        self.resume = resume
        self.progress = sys.stderr.isatty() if progress is None else progress
        self.log = log or (lambda message: print(message, file=sys.stderr))
        self.on_evaluation = on_evaluation
        if resume:
            if run_dir is None:
                raise RunDirError("--resume needs --run-dir (the run to continue)")
            self.run_dir = Path(run_dir)
            self.lock = lock_run_dir(self.run_dir, new_run=False)
            saved = self.run_dir / "config.yaml"
            if not saved.is_file():
                self.lock.release()
                raise RunDirError(f"cannot resume {self.run_dir}: no config.yaml there")
            self.config = runconfig.resolve(runconfig.merge(runconfig.load(saved), overrides))
            try:
                steps, path, _skipped = _core.resume_point(json.dumps(self.config), self.lock)
            except ValueError as error:
                self.lock.release()
                raise RunDirError(str(error)) from None
            # The skipped checkpoints are named when training starts (the observer's on_note).
            self.resume_from: tuple[int, Path] | None = (steps, Path(path))
        else:
            self.config = runconfig.resolve(overrides)
            self.run_dir = Path(run_dir) if run_dir is not None else default_run_dir(self.config)
            self.lock = lock_run_dir(self.run_dir, new_run=True)
            self.resume_from = None

    def run(self) -> TrainResult:
        import numpy

        versions = {"python": platform.python_version(), "numpy": numpy.__version__}
        progress = _Progress(self.progress, self.log, self.on_evaluation)
        started = time.perf_counter()
        try:
            result = _core.train(
                json.dumps(self.config), self.lock, self.resume, json.dumps(versions), progress
            )
        except (ValueError, OSError) as error:
            # Setup problems (ValueError) and unwritable run directories (OSError): one line each.
            raise RunDirError(str(error)) from None
        except RuntimeError as error:
            raise TrainingFailed(str(error)) from None
        finally:
            progress.close()
            self.lock.release()
        if result["interrupted"]:
            raise TrainingInterrupted(result["timesteps"], Path(result["checkpoint"]))
        return TrainResult(
            run_dir=self.run_dir,
            start_timesteps=result["start_timesteps"],
            timesteps=result["timesteps"],
            seconds=time.perf_counter() - started,
            eval_seconds=result["eval_seconds"],
            last_evaluation=result["last_evaluation"],
            details=result,
        )
