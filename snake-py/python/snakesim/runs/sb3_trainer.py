"""Training PPO on snakesim as the paper did (Stable-Baselines3), with evaluations, checkpoints and resume.

A run lives in one directory::

    config.yaml          the resolved configuration (seeds included); reloads equal
    versions.json        snakesim, stable-baselines3, torch, gymnasium, numpy and Python versions
    evaluations.csv      timesteps, mean_return, std_return, success_rate, mean_steps_to_goal, wall_time
    tb/PPO_1/            TensorBoard logs (SB3's, plus eval/*)
    checkpoints/         model_<T>_steps.zip (+ vecnormalize_<T>_steps.pkl, model_<T>_steps.json)
    model.zip            the final model (also written on Ctrl-C), vecnormalize.pkl with normalize: true
    writer.lock          who writes the run now: one writer per run directory (snakesim._core.lock_run_dir)

Every file is written whole, through a temporary file renamed into place, or appended a row at a time,
so readers (evaluate, plot, replay) need no lock and never see half a file.

Evaluations run every ``eval_freq`` total timesteps and once at the end, on ``eval_episodes``
deterministic episodes in a separate batched env seeded with ``eval_seed``: every evaluation sees the
same start states, so successive points of a learning curve differ by the policy alone.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import platform
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from snakesim import _core, extras
from snakesim.agents.evaluation import run_episodes, summarize
from snakesim.agents.loading import (
    EXPORTED_ENV_KEY,
    RECORDED_FILES_KEY,
    AgentError,
    inspect_model,
    load_normalizer,
    recorded_env_files,
    safe_custom_objects,
)
from snakesim.envs.config import env_file_records
from snakesim.files import open_regular, read_text, rewrite_atomically
from snakesim.runs import config as runconfig
from snakesim.runs import rundir
from snakesim.runs.results import TrainingInterrupted, TrainResult, format_eval
from snakesim.runs.rundir import (
    EVAL_FIELDS,
    EVALUATIONS_FILE,
    TB_DIR,
    TB_NAME,
    VERSIONS_FILE,
    RunDirError,
    default_run_dir,
    lock_run_dir,
)


def package_versions() -> dict[str, str]:
    import gymnasium
    import numpy
    import stable_baselines3
    import torch

    return {
        "snakesim": _core.__version__,
        "stable_baselines3": stable_baselines3.__version__,
        "torch": torch.__version__,
        "gymnasium": gymnasium.__version__,
        "numpy": numpy.__version__,
        "python": platform.python_version(),
    }


class _Callback:
    """Builds SB3 callbacks lazily, so that importing this module does not import SB3."""

    @staticmethod
    def classes():
        from stable_baselines3.common.callbacks import BaseCallback

        class Periodic(BaseCallback):
            """Calls ``action(num_timesteps)`` whenever the total timesteps cross a multiple of ``every``."""

            def __init__(self, every: int, action: Callable[[int], None]) -> None:
                super().__init__()
                self.every = every
                self.action = action
                self.next_at = 0

            def _on_training_start(self) -> None:
                self.next_at = (self.num_timesteps // self.every + 1) * self.every

            def _on_step(self) -> bool:
                if self.num_timesteps >= self.next_at:
                    self.action(self.num_timesteps)
                    self.next_at = (self.num_timesteps // self.every + 1) * self.every
                return True

        class Progress(BaseCallback):
            """A tqdm bar of total timesteps with timesteps/s and the latest evaluation."""

            def __init__(self, total: int, trainer: Trainer) -> None:
                super().__init__()
                self.total = total
                self.trainer = trainer
                self.bar = None
                self.shown = 0

            def _on_training_start(self) -> None:
                from tqdm import tqdm

                self.shown = self.num_timesteps
                self.bar = tqdm(
                    total=self.total,
                    initial=self.shown,
                    unit="step",
                    unit_scale=True,
                    dynamic_ncols=True,
                    file=sys.stderr,
                    desc="train",
                )

            def _on_step(self) -> bool:
                if self.bar is not None:
                    self.bar.update(self.num_timesteps - self.shown)
                    self.shown = self.num_timesteps
                return True

            def refresh(self) -> None:
                if self.bar is not None and self.trainer.last_evaluation is not None:
                    self.bar.set_postfix_str(format_eval(self.trainer.last_evaluation))

            def close(self) -> None:
                if self.bar is not None:
                    self.bar.close()
                    self.bar = None

        return Periodic, Progress


class Trainer:
    """One training session of a run: a new run, or ``resume=True`` to continue a run directory.

    ``overrides`` are configuration keys (YAML + command line) over the defaults, or over the run's
    saved config.yaml when resuming (keys that define what is learnt cannot change then).
    ``callbacks`` are extra SB3 callbacks; ``on_evaluation`` is called with each evaluation row as it
    is written.
    """

    def __init__(
        self,
        overrides: Mapping[str, Any],
        run_dir: str | os.PathLike | None = None,
        *,
        resume: bool = False,
        progress: bool | None = None,
        verbose: int = 0,
        callbacks: Sequence[Any] = (),
        log: Callable[[str], None] | None = None,
        on_evaluation: Callable[[dict[str, Any]], None] | None = None,
    ) -> None:
        extras.require("sb3", "the SB3 trainer (trainer: sb3; the default, native, needs no extra)")
        self.resume = resume
        self.on_evaluation = on_evaluation
        self.verbose = verbose
        self.progress = sys.stderr.isatty() if progress is None else progress
        self.extra_callbacks = list(callbacks)
        self.log = log or (lambda message: print(message, file=sys.stderr))
        self.last_evaluation: dict[str, Any] | None = None
        self.eval_seconds = 0.0
        self.resume_from: tuple[int, Path] | None = None
        self.wall_offset = 0.0

        if resume:
            if run_dir is None:
                raise RunDirError("--resume needs --run-dir (the run to continue)")
            self.run_dir = Path(run_dir)
            self.lock = lock_run_dir(self.run_dir, new_run=False)
            try:
                config = self._resume_config(overrides)
            except BaseException:
                self.lock.release()
                raise
        else:
            config = runconfig.resolve(overrides)
            self.run_dir = Path(run_dir) if run_dir is not None else default_run_dir(config)
            self.lock = lock_run_dir(self.run_dir, new_run=True)
        self.config = config

    def _resume_config(self, overrides: Mapping[str, Any]) -> dict[str, Any]:
        """The saved configuration with ``overrides``; picks the newest checkpoint that is whole (its
        zip readable, its note parsed), naming each newer one it skips."""
        config_path = self.run_dir / rundir.CONFIG_FILE
        if not config_path.is_file():
            raise RunDirError(f"cannot resume {self.run_dir}: no {rundir.CONFIG_FILE} there")
        saved = runconfig.load(config_path)
        config = runconfig.resolve(runconfig.merge(saved, overrides))
        for key in runconfig.IDENTITY_KEYS:
            # Optional tables (steer_assist, init) are left out of a configuration while unset.
            if config.get(key) != saved.get(key):
                raise RunDirError(
                    f"cannot change {key} when resuming "
                    f"({self.run_dir} has {saved.get(key)!r}, got {config.get(key)!r})"
                )
        found = rundir.checkpoints(self.run_dir)
        if not found:
            raise RunDirError(f"cannot resume {self.run_dir}: it has no checkpoints")
        skipped = []
        for steps, path in reversed(found):
            meta = path.with_suffix(".json")
            try:
                inspect_model(path)
            except AgentError as error:
                skipped.append(f"skipped a checkpoint: {error}")
                continue
            try:
                wall = 0.0
                if meta.is_file():
                    wall = float(json.loads(read_text(meta, "config_bytes"))["wall_time"])
                if not math.isfinite(wall) or wall < 0:
                    raise ValueError(f"wall_time {wall} is not a time")
            except (ValueError, TypeError, KeyError, OSError) as error:
                skipped.append(f"skipped a checkpoint: {meta} is corrupt ({type(error).__name__}: {error})")
                continue
            if steps >= config["timesteps"]:
                raise RunDirError(
                    f"{self.run_dir} already has {steps} timesteps (>= timesteps "
                    f"{config['timesteps']}); pass a larger --timesteps to train on"
                )
            for line in skipped:
                self.log(f"note: {line}")
            self.resume_from = (steps, path)
            self.wall_offset = wall
            return config
        raise RunDirError(
            f"cannot resume {self.run_dir}: none of its checkpoints loads ({'; '.join(skipped)})"
        )

    # -- files -------------------------------------------------------------------------------------
    def _prepare_dir(self) -> None:
        try:
            (self.run_dir / rundir.CHECKPOINT_DIR).mkdir(parents=True, exist_ok=True)
            runconfig.save(self.config, self.run_dir / rundir.CONFIG_FILE)
            versions_path = self.run_dir / VERSIONS_FILE
            versions = package_versions()
            if self.resume and versions_path.is_file():
                recorded = json.loads(read_text(versions_path, "config_bytes"))
                current = {k: v for k, v in versions.items() if recorded.get(k) != v}
                if current:
                    recorded.setdefault("resumed_with", []).append(
                        {"timesteps": self.resume_from[0] if self.resume_from else 0, **current}
                    )
                    self.log(f"note: resuming with other versions than the run started with: {current}")
                versions = recorded
            rewrite_atomically(
                versions_path, lambda tmp: Path(tmp).write_text(json.dumps(versions, indent=2) + "\n")
            )
            self._prepare_evaluations()
        except OSError as error:
            raise RunDirError(
                f"cannot write to run directory {self.run_dir}: {error.strerror or error}"
            ) from None

    def _prepare_evaluations(self) -> None:
        path = self.run_dir / EVALUATIONS_FILE
        rows: list[list[str]] = []
        if self.resume and path.is_file():
            # Evaluations after the checkpoint we resume from (a crash after it) are redone: drop them.
            with io.TextIOWrapper(open_regular(path, "csv_bytes"), encoding="utf-8", newline="") as f:
                reader = csv.reader(f)
                next(reader, None)
                limit = self.resume_from[0] if self.resume_from else 0
                for row in reader:
                    if not row:
                        continue
                    try:
                        values = [float(cell) for cell in row]
                    except ValueError:
                        values = []
                    if len(values) != len(EVAL_FIELDS):
                        raise RunDirError(rundir.bad_row(path, reader.line_num, row))
                    if values[0] <= limit:
                        rows.append(row)

        def write(tmp: str) -> None:
            with open(tmp, "w", newline="", encoding="utf-8") as f:
                writer = csv.writer(f)
                writer.writerow(EVAL_FIELDS)
                writer.writerows(rows)

        rewrite_atomically(path, write)

    def _append_evaluation(self, row: Mapping[str, Any]) -> None:
        with open(self.run_dir / EVALUATIONS_FILE, "a", newline="", encoding="utf-8") as f:
            csv.writer(f).writerow([rundir.csv_value(row[key]) for key in EVAL_FIELDS])

    def wall_time(self) -> float:
        return self.wall_offset + (time.perf_counter() - self.started)

    # -- model -------------------------------------------------------------------------------------
    def _resumed_env(self, env_kwargs: dict[str, Any], checkpoint: Path) -> dict[str, Any]:
        """The env keywords a resumed run goes on with: the configuration's, with the record of the
        checkpoint in place of a robot or world file that changed since it was written (one note
        each), so that the run goes on with the robot it trained on, as a loaded model acts on it."""
        from snakesim.envs.config import apply_env_files

        records = recorded_env_files(checkpoint)
        if records is None:
            return env_kwargs
        try:
            env_kwargs, notes = apply_env_files(env_kwargs, records)
        except (TypeError, ValueError) as error:
            raise RunDirError(f"{checkpoint}: {error}") from None
        for line in notes:
            self.log(f"note: {checkpoint}: {line}")
        return env_kwargs

    def _make_env(self):
        from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

        from snakesim.envs.sb3 import SnakeVecEnv

        env_kwargs = runconfig.env_kwargs(self.config)
        if self.resume_from is not None:
            env_kwargs = self._resumed_env(env_kwargs, self.resume_from[1])
        venv = VecMonitor(SnakeVecEnv(self.config["n_envs"], **env_kwargs))
        # The env keywords (its `randomize` included) and the texts of the robot and world files the
        # envs are built from, recorded in every zip saved, so a zip copied out of its run keeps them.
        self.env_kwargs = env_kwargs
        self.env_files = env_file_records(env_kwargs)
        if not self.config["normalize"]:
            return venv
        if self.resume_from is not None:
            stats = rundir.checkpoint_paths(self.run_dir, self.resume_from[0])[1]
            if stats.is_file():
                # VecNormalize.load, but unpickled through the allow-list of snakesim.agents.safe_pickle.
                try:
                    normalizer = load_normalizer(stats)
                except AgentError as error:
                    raise RunDirError(f"cannot resume {self.run_dir}: {error}") from None
                normalizer.set_venv(venv)
                normalizer.training = True
                return normalizer
            self.log(f"note: {stats} is missing; observation statistics start afresh")
        return VecNormalize(venv, gamma=self.config["ppo"]["gamma"])

    def _unpickled(self, path: Path, venv) -> dict[str, Any]:
        """What replaces the pickled entries of a checkpoint's ``data`` (SB3 would unpickle them, and a
        pickle can run code): the same things, made from the configuration and the env."""
        from stable_baselines3.common.policies import ActorCriticPolicy

        from snakesim.runs.policies import policy_kwargs

        ppo = self.config["ppo"]
        known = {
            "policy_class": ActorCriticPolicy,  # what "MlpPolicy" names
            "policy_kwargs": policy_kwargs(self.config["arch"], log_std_init=self.config["log_std_init"]),
            "observation_space": venv.observation_space,
            "action_space": venv.action_space,
            "learning_rate": runconfig.schedule(ppo["learning_rate"]),
            "clip_range": runconfig.schedule(ppo["clip_range"]),
            "clip_range_vf": runconfig.schedule(ppo["clip_range_vf"]),  # None stays None
        }
        try:
            return safe_custom_objects(path, known)
        except AgentError as error:
            raise RunDirError(f"cannot resume {self.run_dir}: {error}") from None

    def _make_model(self, venv):
        from stable_baselines3 import PPO

        from snakesim.runs.policies import policy_kwargs

        tb = os.fspath(self.run_dir / TB_DIR)
        if self.resume_from is not None:
            steps, path = self.resume_from
            try:
                model = PPO.load(
                    path,
                    env=venv,
                    device=self.config["device"],
                    custom_objects=self._unpickled(path, venv),
                    tensorboard_log=tb,
                    verbose=self.verbose,
                )
            except Exception as error:  # noqa: BLE001 - a corrupt zip fails in torch or pickle in many ways
                first = (str(error).strip().splitlines() or [""])[0]
                raise RunDirError(
                    f"cannot resume {self.run_dir}: {path} is not a loadable checkpoint "
                    f"({type(error).__name__}: {first}); delete it to resume from the one before"
                ) from None
            # A fresh env: start new episodes (the saved last observation belongs to the old env), and
            # seed them apart from the episodes seen before.
            model._last_obs = None
            model.set_random_seed(self.config["seed"] + steps)
            return model
        return PPO(
            "MlpPolicy",
            venv,
            policy_kwargs=policy_kwargs(self.config["arch"], log_std_init=self.config["log_std_init"]),
            seed=self.config["seed"],
            device=self.config["device"],
            tensorboard_log=tb,
            verbose=self.verbose,
            **{
                key: runconfig.schedule(value) if key in ("learning_rate", "clip_range") else value
                for key, value in self.config["ppo"].items()
            },
        )

    def save_checkpoint(self, timesteps: int, reason: str = "periodic") -> Path:
        model_path, stats_path = rundir.checkpoint_paths(self.run_dir, timesteps)
        self._save_model(model_path, stats_path)
        meta = {"timesteps": timesteps, "wall_time": self.wall_time(), "reason": reason}
        rewrite_atomically(
            model_path.with_suffix(".json"), lambda tmp: Path(tmp).write_text(json.dumps(meta) + "\n")
        )
        return model_path

    def _save_model(self, model_path: Path, stats_path: Path) -> None:
        """The model zip and, with ``normalize``, its statistics, each written whole (readers may be
        loading them while we train)."""
        rewrite_atomically(model_path, self.model.save)
        normalizer = self.model.get_vec_normalize_env()
        if normalizer is not None:
            rewrite_atomically(stats_path, normalizer.save)

    def _save_final(self) -> Path:
        path = self.run_dir / rundir.MODEL_FILE
        self._save_model(path, self.run_dir / rundir.VECNORMALIZE_FILE)
        return path

    def evaluate(self, timesteps: int) -> dict[str, Any]:
        start = time.perf_counter()
        normalizer = self.model.get_vec_normalize_env()

        def act(obs):
            if normalizer is not None:
                obs = normalizer.normalize_obs(obs)
            return self.model.predict(obs, deterministic=True)[0]

        episodes = run_episodes(
            act, runconfig.env_kwargs(self.config), self.config["eval_episodes"], self.config["eval_seed"]
        )
        summary = summarize(episodes)
        row = {**summary, "timesteps": timesteps, "wall_time": round(self.wall_time(), 3)}
        self._append_evaluation(row)
        logger = self.model.logger
        logger.record("eval/mean_reward", summary["mean_return"])
        logger.record("eval/std_reward", summary["std_return"])
        logger.record("eval/success_rate", summary["success_rate"])
        logger.record("eval/mean_ep_length", summary["mean_length"])
        if summary["mean_steps_to_goal"] is not None:
            logger.record("eval/mean_steps_to_goal", summary["mean_steps_to_goal"])
        logger.record("eval/mean_speed", summary["mean_speed"])
        logger.dump(timesteps)
        self.last_evaluation = row
        self.last_eval_timesteps = timesteps
        if self.progress_callback is not None:
            self.progress_callback.refresh()
        elif self.verbose:
            self.log(f"{timesteps} timesteps: {format_eval(row)}")
        self.eval_seconds += time.perf_counter() - start
        if self.on_evaluation is not None:
            self.on_evaluation(dict(row))
        return row

    # -- the session -------------------------------------------------------------------------------
    def run(self) -> TrainResult:
        """Trains to the configured timesteps; the run directory's lock is let go when it returns."""
        try:
            return self._run()
        finally:
            self.lock.release()

    def _run(self) -> TrainResult:
        import torch
        from stable_baselines3.common.callbacks import CallbackList

        target = self.config["timesteps"]
        if self.config["torch_threads"] is not None:
            torch.set_num_threads(self.config["torch_threads"])
        self._prepare_dir()
        self.started = time.perf_counter()
        venv = self._make_env()
        self.model = self._make_model(venv)
        # Plain JSON in the zip's data, as `snakesim export` writes them (PPO.load sets each as an
        # attribute and ignores it; snakesim's loader reads them for a zip without its run directory).
        setattr(self.model, EXPORTED_ENV_KEY, dict(self.env_kwargs))
        if self.env_files is not None:
            setattr(self.model, RECORDED_FILES_KEY, self.env_files)
        start_timesteps = self.model.num_timesteps
        self.last_eval_timesteps = -1
        Periodic, Progress = _Callback.classes()
        callbacks: list[Any] = []
        self.progress_callback = Progress(target, self) if self.progress else None
        if self.progress_callback is not None:
            callbacks.append(self.progress_callback)
        if self.config["eval_freq"] > 0:
            callbacks.append(Periodic(self.config["eval_freq"], self.evaluate))
        if self.config["checkpoint_freq"] > 0:
            callbacks.append(Periodic(self.config["checkpoint_freq"], self.save_checkpoint))
        callbacks += self.extra_callbacks

        train_start = time.perf_counter()
        try:
            self.model.learn(
                total_timesteps=target - start_timesteps,
                callback=CallbackList(callbacks),
                reset_num_timesteps=self.resume_from is None,
                tb_log_name=TB_NAME,
            )
            if self.last_eval_timesteps != self.model.num_timesteps:
                self.evaluate(self.model.num_timesteps)
        except KeyboardInterrupt:
            if self.progress_callback is not None:
                self.progress_callback.close()
            steps = self.model.num_timesteps
            path = self.save_checkpoint(steps, reason="interrupt")
            self._save_final()
            raise TrainingInterrupted(steps, path) from None
        finally:
            if self.progress_callback is not None:
                self.progress_callback.close()
            venv.close()
        self.save_checkpoint(self.model.num_timesteps, reason="final")
        self._save_final()
        seconds = time.perf_counter() - train_start
        return TrainResult(
            run_dir=self.run_dir,
            start_timesteps=start_timesteps,
            timesteps=self.model.num_timesteps,
            seconds=seconds,
            eval_seconds=self.eval_seconds,
            last_evaluation=self.last_evaluation,
        )
