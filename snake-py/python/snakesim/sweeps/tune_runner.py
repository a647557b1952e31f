"""The Ray side of sweeps and searches: connecting to a cluster, the Tune trainable that trains one
trial in its run directory, and the progress display.

A trial reports every periodic evaluation of its run to Tune as it is written (``timesteps``,
``mean_return``, ``success_rate``, ...). Its checkpoints are the run's own: with a report after a new
checkpoint of the run, Tune gets a small checkpoint that points at it. A retried trial (its worker
died; ``--max-failures``) finds its run directory and resumes it from the latest checkpoint through the
trainers' own resume, so the run folder must be reachable at the same path from every node (one
machine, or a shared file system: see docs/sweeps.md).
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import json
import logging
import os
import re
import shutil
import signal
import socket
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from snakesim import extras
from snakesim.runs.progress import Progress, clock
from snakesim.sweeps.plan import (
    CONNECT_TIMEOUT_S,
    TRIAL_LOCK_WAIT_S,
    TUNE_DIR,
    SweepError,
    Trial,
    lock_folder,
    next_session,
    trial_finished,
)

extras.require("sweep")

#: Each training session of a trial, one JSON line, in its run directory.
SESSIONS_FILE = "sessions.jsonl"
#: What a trial reports to Tune from each evaluation row.
METRICS = ("timesteps", "mean_return", "std_return", "success_rate", "mean_steps_to_goal", "wall_time")


@dataclasses.dataclass
class Outcome:
    """What a Tune session ended with: the final error of each failed trial, and whether Ctrl-C
    stopped it."""

    errors: dict[str, str] = dataclasses.field(default_factory=dict)
    interrupted: bool = False


# -- connecting -----------------------------------------------------------------------------------
def _host_port(address: str) -> tuple[str, int]:
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise SweepError(f"--address {address!r}: expected HOST:PORT (what `ray start --head` prints)")
    return host.strip("[]"), int(port)


@contextlib.contextmanager
def _stderr_silenced():
    """Ray's C++ core logs every failed attempt to reach a cluster on stderr (a line a second);
    while connecting, our one-line error says it instead."""
    sys.stderr.flush()
    saved = os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)
    os.close(devnull)
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)


def _quiet_ray_init(**kwargs: Any) -> None:
    import ray

    ray.init(include_dashboard=False, logging_level=logging.ERROR, log_to_driver=False, **kwargs)


def _ray_token_exists() -> bool:
    """Whether a Ray authentication token is at hand where Ray's documentation says Ray looks for one:
    ``RAY_AUTH_TOKEN``, the file ``RAY_AUTH_TOKEN_PATH`` names, or ``~/.ray/auth_token``."""
    if os.environ.get("RAY_AUTH_TOKEN"):
        return True
    path = os.environ.get("RAY_AUTH_TOKEN_PATH") or os.path.join(
        os.path.expanduser("~"), ".ray", "auth_token"
    )
    return os.path.isfile(path)


@contextlib.contextmanager
def _token_auth_if_available(address: str | None):
    """Ray turns token authentication on by itself when it starts a local cluster or finds one, if
    a token exists, but not for an explicit address: a cluster started with `ray start` by the same
    user would refuse us. Do as Ray does for local clusters (a cluster without authentication accepts
    a driver that has a token), through Ray's public switch ``RAY_AUTH_MODE=token``, set for as long as
    the driver is connected and restored afterwards. Ray reads it when it is first imported, so a
    process that imported Ray before (a library user) sets ``RAY_AUTH_MODE=token`` itself."""
    if address is None or "RAY_AUTH_MODE" in os.environ or not _ray_token_exists():
        yield
        return
    os.environ["RAY_AUTH_MODE"] = "token"
    try:
        yield
    finally:
        os.environ.pop("RAY_AUTH_MODE", None)


#: Bytes Ray adds below its temp folder for its longest socket path (session_..._<pid>/sockets/plasma_store).
RAY_SESSION_PATH_BYTES = 64


def _local_ray_scratch() -> str:
    """A folder for the local Ray's session files (logs, sockets, object spills), removed when this
    process ends: Ray's own default, /tmp/ray, keeps every session's files forever."""
    import atexit

    import ray

    # Ray puts sockets at <folder>/session_<date>_<time>_<pid>/sockets/plasma_store, and a socket's
    # path may not exceed 107 bytes: a long TMPDIR falls back to /tmp, Ray's own default parent.
    parent = tempfile.gettempdir()
    if len(parent) + len("/snakesim-ray-12345678") + RAY_SESSION_PATH_BYTES > 107:
        parent = "/tmp"
    scratch = tempfile.mkdtemp(prefix="snakesim-ray-", dir=parent)

    def remove() -> None:
        # Ray's own exit hook (registered later, so run earlier) has stopped it already; stopping twice
        # is harmless, and Ray must be down before its files go.
        ray.shutdown()
        shutil.rmtree(scratch, ignore_errors=True)

    atexit.register(remove)
    return scratch


@contextlib.contextmanager
def connected(address: str | None, cpus_per_trial: int = 1, timeout: float = CONNECT_TIMEOUT_S):
    """:func:`connect` for the block, which gets the description: when it ends, this process leaves
    Ray and the settings it changed for Ray are restored."""
    # Ray reads RAY_AUTH_MODE into its configuration when it is first imported: switch first.
    with _token_auth_if_available(address):
        import ray

        try:
            yield connect(address, cpus_per_trial, timeout)
        finally:
            if ray.is_initialized():
                ray.shutdown()


def connect(address: str | None, cpus_per_trial: int = 1, timeout: float = CONNECT_TIMEOUT_S) -> str:
    """Connects this process to Ray: the cluster at ``address`` (HOST:PORT), or a local Ray started
    for the sweep; checks that it has ``cpus_per_trial`` CPUs. Returns a description; SweepError
    within ``timeout`` seconds when nothing answers."""
    import ray

    if ray.is_initialized():
        ray.shutdown()
    if address is None:
        _quiet_ray_init(_temp_dir=_local_ray_scratch())
        _check_cpus(cpus_per_trial)
        return f"a local Ray ({_cpus()} CPUs)"
    host, port = _host_port(address)
    started = time.monotonic()
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as error:
        reason = "timed out" if isinstance(error, socket.timeout) else (error.strerror or str(error))
        raise SweepError(f"cannot reach a Ray cluster at {address}: {reason}") from None
    # Something listens; Ray itself retries for minutes when it is not Ray: wait for it no longer.
    failure: list[BaseException] = []

    def init() -> None:
        try:
            _quiet_ray_init(address=f"{host}:{port}")
        except BaseException as error:  # noqa: BLE001 - handed to the waiting thread
            failure.append(error)

    with _stderr_silenced():
        thread = threading.Thread(target=init, name="snakesim-ray-connect", daemon=True)
        thread.start()
        thread.join(max(0.0, timeout - (time.monotonic() - started)))
    if thread.is_alive():
        raise SweepError(f"no Ray cluster answered at {address} within {timeout:g} s")
    if failure:
        raise SweepError(f"cannot connect to the Ray cluster at {address}: {_last_line(str(failure[0]))}")
    _check_cpus(cpus_per_trial)
    return f"the Ray cluster at {address} ({_cpus()} CPUs)"


def _cpus() -> int:
    import ray

    return int(ray.cluster_resources().get("CPU", 0))


def _check_cpus(cpus_per_trial: int) -> None:
    cpus = _cpus()
    if cpus < cpus_per_trial:
        raise SweepError(f"--cpus-per-trial {cpus_per_trial} is more than the cluster's {cpus} CPUs")


def _last_line(text: str, limit: int = 300) -> str:
    """The line of a traceback that names the error (``SomeError: message``), else its last line."""
    lines = [line.strip() for line in text.strip().splitlines() if line.strip()]
    named = [line for line in lines if re.match(r"^[\w.]+(Error|Exception|Failed|Interrupted)\b", line)]
    line = named[-1] if named else (lines[-1] if lines else "unknown error")
    return line if len(line) <= limit else line[: limit - 3] + "..."


# -- the trainable (runs on the workers) ----------------------------------------------------------
def _metrics(history: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """What Tune hears of a run's latest evaluation: its row's METRICS and the derived success_auc
    (``history``: all the run's evaluations so far, in timestep order)."""
    from snakesim.sweeps.summary import SUCCESS_AUC, with_success_auc

    last = with_success_auc([dict(r) for r in history])[-1]
    return {**{key: last.get(key) for key in METRICS}, SUCCESS_AUC: last[SUCCESS_AUC]}


class _Reporter:
    """Hands each evaluation of a trial's run to Tune, with a pointer to the run's newest checkpoint
    when there is a new one."""

    def __init__(self, run_dir: Path, native: bool, name: str, started_from: int, earlier: str = "") -> None:
        self.run_dir = run_dir
        self.earlier = earlier  # sessions.jsonl of attempts whose folder was cleared
        self.native = native
        self.name = name
        self.started_from = started_from
        self.reported_checkpoint = started_from
        self.session_noted = False
        self.started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")

    def note_session(self) -> None:
        """One line in sessions.jsonl: when, where and from which timesteps this session trained
        (written once the run's folder exists: a new run's from its first evaluation on)."""
        if self.session_noted:
            return
        self.session_noted = True
        line = {
            "started": self.started,
            "resumed_from": self.started_from,
            "host": socket.gethostname(),
            "pid": os.getpid(),
        }
        with open(self.run_dir / SESSIONS_FILE, "a", encoding="utf-8") as f:
            f.write(self.earlier + json.dumps(line) + "\n")

    def __call__(self, row: Mapping[str, Any]) -> None:
        from ray import tune

        from snakesim.runs import rundir
        from snakesim.sweeps.summary import evaluations

        self.note_session()  # a new run's folder exists from its first evaluation on
        # The run's earlier evaluations (a resumed trial's included) and this one, whether or not the
        # trainer has written it to evaluations.csv yet.
        history = [r for r in evaluations(self.run_dir) if r["timesteps"] < row["timesteps"]]
        metrics = _metrics([*history, dict(row)])
        metrics["resumed_from"] = self.started_from
        found = rundir.checkpoints(self.run_dir, native=self.native)
        if not found or found[-1][0] <= self.reported_checkpoint:
            tune.report(metrics)
            return
        steps = found[-1][0]
        with tempfile.TemporaryDirectory(prefix="snakesim-checkpoint-") as folder:
            pointer = {"run_dir": str(self.run_dir), "checkpoint": str(found[-1][1]), "timesteps": steps}
            (Path(folder) / "run_checkpoint.json").write_text(json.dumps(pointer) + "\n")
            tune.report(metrics, checkpoint=tune.Checkpoint.from_directory(folder))
        self.reported_checkpoint = steps


def train_trial(param: Mapping[str, Any]) -> None:
    """The Tune trainable: trains ``param["trial"]`` (name, run_dir, overrides) in its run directory,
    resuming it when it has checkpoints (a retry, or a resumed sweep)."""
    from ray import tune

    from snakesim.runs import config as runconfig
    from snakesim.runs import rundir

    spec = param["trial"]
    run_dir = Path(spec["run_dir"])
    config = runconfig.resolve(spec["overrides"])
    native = config["trainer"] == "native"
    if run_dir.is_dir():
        # A retry, or a resumed sweep: the earlier attempt's worker may still be ending (Ray gave up on
        # it, it did not die). Wait for it to let go of the folder; never write beside it. (The
        # trainer takes the lock again for itself below.)
        lock_folder(run_dir, TRIAL_LOCK_WAIT_S, "run directory").release()
    if trial_finished(run_dir):
        # Trained to the end by an earlier attempt that died before Tune heard of it.
        from snakesim.runs.rundir import EVALUATIONS_FILE, read_evaluations

        rows = read_evaluations(run_dir / EVALUATIONS_FILE)
        if rows:
            tune.report(_metrics(sorted(rows, key=lambda r: r["timesteps"])))
        return
    found = rundir.checkpoints(run_dir, native=native)
    resume = bool(found) and (run_dir / rundir.CONFIG_FILE).is_file()
    earlier = ""
    if not resume and run_dir.exists():
        # An attempt that died before its first checkpoint: start again (the trainers want an empty
        # folder), keeping the record of its session.
        sessions = run_dir / SESSIONS_FILE
        earlier = sessions.read_text(encoding="utf-8") if sessions.is_file() else ""
        shutil.rmtree(run_dir)
    reporter = _Reporter(run_dir, native, spec["name"], found[-1][0] if resume else 0, earlier)
    # Both trainers log to stderr: the worker's log file in Ray's log folder.
    if native:
        from snakesim.runs.native import NativeTrainer

        trainer: Any = NativeTrainer(
            spec["overrides"], run_dir, resume=resume, progress=False, on_evaluation=reporter
        )
    else:
        from snakesim.runs.sb3_trainer import Trainer

        trainer = Trainer(spec["overrides"], run_dir, resume=resume, progress=False, on_evaluation=reporter)
    if resume:
        reporter.note_session()
    trainer.run()
    reporter.note_session()


# -- the driver -----------------------------------------------------------------------------------
class _Display:
    """Trials running / done / failed of the total, on stderr: on a terminal a bar of finished trials
    with the elapsed time and an estimate of the time left (tqdm), the counts and the latest result
    beside it; otherwise a line whenever the counts change, with the elapsed time and the estimate."""

    def __init__(self, total: int, show: bool, tty: bool) -> None:
        self.total = total
        self.show = show
        self.tty = tty
        self.state: dict[str, str] = {}
        self.retries = 0
        self.latest = ""
        self.last_line = ""
        self.start = time.monotonic()
        self.bar: Progress | None = None
        if show and tty:
            self.bar = Progress(total, "trials", "sweep", show=True)

    def set(self, name: str, state: str) -> None:
        self.state[name] = state
        self.draw()

    def result(self, name: str, result: Mapping[str, Any]) -> None:
        if result.get("timesteps") is not None and result.get("success_rate") is not None:
            self.latest = (
                f"; {name}: {int(result['timesteps']):,} timesteps, success {result['success_rate']:.2f}"
            )
        if self.tty:
            self.draw()

    def counts(self) -> dict[str, int]:
        return {s: sum(1 for v in self.state.values() if v == s) for s in ("running", "done", "failed")}

    def line(self) -> str:
        counts = self.counts()
        waiting = self.total - sum(counts.values())
        text = (
            f"trials: {counts['running']} running, {counts['done']} done, {counts['failed']} failed, "
            f"{waiting} waiting (of {self.total})"
        )
        if self.retries:
            text += f", {self.retries} retried"
        return text

    def timing(self) -> str:
        """``M:SS elapsed, about M:SS left``: the time left from the finished trials' pace."""
        counts = self.counts()
        finished = counts["done"] + counts["failed"]
        elapsed = time.monotonic() - self.start
        text = f"{clock(elapsed)} elapsed"
        if 0 < finished < self.total:
            text += f", about {clock(elapsed * (self.total - finished) / finished)} left"
        return text

    def draw(self) -> None:
        if not self.show:
            return
        text = self.line()
        if self.bar is not None:
            counts = self.counts()
            self.bar.update(counts["done"] + counts["failed"], (text + self.latest).removeprefix("trials: "))
        elif text != self.last_line:
            print(f"{text}, {self.timing()}", file=sys.stderr, flush=True)
        self.last_line = text

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _tune_callback(display: _Display, names: Callable[[Any], str]):
    from ray import tune

    class Progress(tune.Callback):
        def on_trial_start(self, iteration, trials, trial, **info):
            display.set(names(trial), "running")

        def on_trial_result(self, iteration, trials, trial, result, **info):
            display.result(names(trial), result)

        def on_trial_recover(self, iteration, trials, trial, **info):
            display.retries += 1
            display.set(names(trial), "waiting")

        def on_trial_complete(self, iteration, trials, trial, **info):
            display.set(names(trial), "done")

        def on_trial_error(self, iteration, trials, trial, **info):
            display.set(names(trial), "failed")

    return Progress()


@contextlib.contextmanager
def scoped_settings(env: Mapping[str, str] | None = None, loggers: Mapping[str, int] | None = None):
    """Sets environment variables and logger levels for the block and restores the process's own
    afterwards: a library call leaves the process as it found it."""
    env, loggers = env or {}, loggers or {}
    saved_env = {key: os.environ.get(key) for key in env}
    saved_levels = {name: logging.getLogger(name).level for name in loggers}
    os.environ.update(env)
    for name, level in loggers.items():
        logging.getLogger(name).setLevel(level)
    try:
        yield
    finally:
        for key, value in saved_env.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        for name, level in saved_levels.items():
            logging.getLogger(name).setLevel(level)


class _CtrlC:
    """The first Ctrl-C stops the trials (Tune ends them and returns); the second one quits at once."""

    def __init__(self) -> None:
        self.pressed = False

    def __enter__(self):
        self.previous = signal.getsignal(signal.SIGINT)
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, self.handle)
        return self

    def handle(self, signum, frame) -> None:
        if self.pressed:
            raise KeyboardInterrupt
        self.pressed = True
        print("\nstopping the trials (Ctrl-C again to quit at once)", file=sys.stderr, flush=True)

    def __exit__(self, *exc) -> None:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, self.previous)

    def stopper(self):
        from ray import tune

        ctrl_c = self

        class StopOnCtrlC(tune.Stopper):
            def __call__(self, trial_id, result):
                return False

            def stop_all(self):
                return ctrl_c.pressed

        return StopOnCtrlC()


def fit(
    out: Path,
    trainable: Any,
    param_space: Mapping[str, Any],
    *,
    total: int,
    names: Callable[[Any], str],
    cpus_per_trial: int,
    max_failures: int,
    progress: bool | None,
    tune_config: Any = None,
) -> Outcome:
    """Runs a Tune experiment in ``out/tune/session-N`` with the progress display; returns the final
    error of each failed trial and whether Ctrl-C stopped it."""
    from ray import tune

    # By default: a bar on a terminal, else a line whenever the counts change (--no-progress: none).
    display = _Display(total, progress is not False, sys.stderr.isatty())
    storage = (out / TUNE_DIR).resolve()
    storage.mkdir(parents=True, exist_ok=True)
    tune_config = tune_config or tune.TuneConfig()
    # A worker trains one trial after another: imports (torch, for SB3) and start-up once per worker.
    tune_config.reuse_actors = True
    tune_config.trial_name_creator = names
    tune_config.trial_dirname_creator = names
    # Tune's tables and error tracebacks: the display and our one-line errors replace them. Tune's own
    # Ctrl-C handler would stop the run without telling us; ours (_CtrlC) tells the stopper.
    quiet = scoped_settings(
        env={"RAY_AIR_NEW_OUTPUT": "0", "TUNE_DISABLE_SIGINT_HANDLER": "1"},
        loggers={"ray.tune": logging.CRITICAL, "ray.train": logging.CRITICAL},
    )
    with quiet, _CtrlC() as ctrl_c:
        tuner = tune.Tuner(
            tune.with_resources(trainable, {"cpu": cpus_per_trial}),
            param_space=dict(param_space),
            tune_config=tune_config,
            run_config=tune.RunConfig(
                name=next_session(out),
                storage_path=str(storage),
                verbose=0,
                stop=ctrl_c.stopper(),
                callbacks=[_tune_callback(display, names)],
                failure_config=tune.FailureConfig(max_failures=max_failures),
                checkpoint_config=tune.CheckpointConfig(num_to_keep=1),
            ),
        )
        display.draw()
        try:
            results = tuner.fit()
        finally:
            display.close()
    errors = {}
    for result in results:
        if result.error is not None:
            name = Path(result.path).name
            errors[name] = _last_line(str(result.error))
    return Outcome(errors=errors, interrupted=ctrl_c.pressed)


def run_trials(
    out: Path, trials: Sequence[Trial], cpus_per_trial: int, max_failures: int, progress: bool | None
) -> Outcome:
    """Runs the trials of a sweep: a Tune grid over them."""
    from ray import tune

    specs = [{"name": t.name, "run_dir": str(t.run_dir(out)), "overrides": t.overrides} for t in trials]
    return fit(
        out,
        train_trial,
        {"trial": tune.grid_search(specs)},
        total=len(specs),
        names=lambda trial: trial.config["trial"]["name"],
        cpus_per_trial=cpus_per_trial,
        max_failures=max_failures,
        progress=progress,
    )
