"""Calibration from a log (``snakesim calibrate``): physics parameters of a robot file fitted so that
the simulated run reproduces a logged one.

The log is a trajectory CSV as ``snake-cli run --output`` writes it (``step,t,base_x,base_y,base_z,
base_qx,base_qy,base_qz,base_qw,q0..q{M-1}``, one row per 1/240 s physics step, the state after that
step) and the targets the joint-target CSV that drove it (``snake-cli run --targets``: ``step,<joint
names>``). Each candidate is simulated by ``_core.simulate_robot``, the run of ``snake-cli run --robot R
--targets T`` with the fitted keys written into the robot file and the world, so a fitted value run
by ``snake-cli run`` gives the simulated trajectory bit for bit.

Error (:func:`trajectory_error`): the mean over the log's steps of

    |p_sim - p_log|^2 / POSITION_SCALE^2  +  mean_j (q_sim_j - q_log_j)^2 / ANGLE_SCALE^2

with p the base position (x, y, z) and q the joint angles, POSITION_SCALE 1 cm and ANGLE_SCALE
0.001 rad (about a 12-bit encoder's step): an error of 1 is a root-mean-square miss of 1 cm of the base,
or of 0.001 rad of every joint. The joints weigh this much because they pin the motor parameters
whatever the ground does (docs/calibration.md: without it, kp and the ground friction trade off).
With ``Problem.window`` the simulated run is cut into windows, each restarted from the logged state at
its start (:mod:`snakesim.runs.calibrate_windows`, multiple shooting): the same error over a run that
cannot drift away from the log, so that a small miss in a parameter stays a small error.

A candidate whose simulation fails (the engine refuses it, or its error is not finite) scores
``math.inf``: CMA-ES ranks it last, and it is never the fit. A calibration none of whose candidates
gives a finite error is refused (:class:`CalibrationError`), as are inputs beyond the limits of
``snake-cli run --targets`` (``LIMITS['target_rows']`` rows, ``LIMITS['csv_bytes']``) and log values
beyond ``LIMITS['position']``.

Optimizer: IPOP-CMA-ES (:mod:`snakesim.runs.calibrate_search`: the ``cmaes`` package, bounded,
restarted with doubled populations until two runs agree) over the fitted keys mapped to [0, 1]
(linearly, or logarithmically where the lower bound is > 0: gains and frictions are scales), each
generation's candidates simulated in parallel processes; then each key's interval
(:mod:`snakesim.runs.calibrate_intervals`). Every simulation can be interrupted: Ctrl-C or SIGTERM
ends one in the main process within 20 ms (``_core.simulate_robot``), and ends the worker processes
at once (:func:`_stop_workers`).
"""

from __future__ import annotations

import concurrent.futures
import json
import math
import multiprocessing
import os
import signal
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from snakesim import _core
from snakesim.files import read_text
from snakesim.limits import LIMITS
from snakesim.runs.arguments import ArgumentError, Keyword
from snakesim.runs.calibrate_intervals import delta_for, intervals
from snakesim.runs.calibrate_search import ipop
from snakesim.runs.calibrate_windows import DT as WINDOW_DT
from snakesim.runs.calibrate_windows import window_states

#: The keys ``fit`` takes (``--fit`` of the command) (snake-core's ``run_targets::Overrides``).
FIT_KEYS: tuple[str, ...] = (
    "motors.kp",
    "motors.kd",
    "motors.max_velocity",
    "ground_friction",
    "lateral_friction",
    "anisotropic_friction.x",
    "anisotropic_friction.y",
    "anisotropic_friction.z",
    "skin_friction.forward",
    "skin_friction.backward",
    "skin_friction.transverse",
    "mass_scale",
    "water.skin_friction",
    "water.drag",
    "water.added_mass",
    "water.added_inertia",
    "water.linear",
)
#: Keys a robot file cannot hold: reported in the JSON and as a comment of the fitted robot file
#: (snake-core's list, the one the fitted file is written by).
NOT_IN_ROBOT_FILE = tuple(_core.NOT_IN_ROBOT_FILE)
#: Most simulations of one calibration (``max_evals``).
MAX_EVALS = LIMITS["calibration_evals"]
POSITION_SCALE = 0.01  # m
ANGLE_SCALE = 0.001  # rad
#: The physics step, s: a log and its targets have one row per step.
DT = 1.0 / 240.0


class CalibrationError(ArgumentError):
    """Bad input: the message names the file or key and the problem, and the argument it came in by
    with its Python name (``fit``, ``max_evals``, ``targets``, ``log``); ``snakesim calibrate`` names
    the flag instead (:meth:`~snakesim.runs.arguments.ArgumentError.naming`)."""


FIT, MAX_EVALS_ARG, TARGETS, LOG = Keyword("fit"), Keyword("max_evals"), Keyword("targets"), Keyword("log")


def parse_fit(items: Sequence[str]) -> dict[str, tuple[float, float]]:
    """``KEY=LOW:HIGH`` items as {key: (low, high)}, checked."""
    bounds: dict[str, tuple[float, float]] = {}
    for item in items:
        key, eq, rng = item.partition("=")
        key = key.strip()
        if not eq or ":" not in rng:
            raise CalibrationError(FIT, f" {item!r}: expected KEY=LOW:HIGH")
        if key not in FIT_KEYS:
            raise CalibrationError(FIT, f" {key!r}: unknown key (known: {', '.join(FIT_KEYS)})")
        if key in bounds:
            raise CalibrationError(FIT, f" {key}: given twice")
        low_s, _, high_s = rng.partition(":")
        try:
            low, high = float(low_s), float(high_s)
        except ValueError:
            raise CalibrationError(FIT, f" {key}: {rng!r} is not LOW:HIGH numbers") from None
        if not (math.isfinite(low) and math.isfinite(high)):
            raise CalibrationError(FIT, f" {key}: bounds must be finite, got {low!r}:{high!r}")
        if not low < high:
            raise CalibrationError(
                FIT, f" {key}: the lower bound {low!r} is not below the upper bound {high!r}"
            )
        if low < 0:
            raise CalibrationError(FIT, f" {key}: bounds must be >= 0, got {low!r}:{high!r}")
        bounds[key] = (low, high)
    if not bounds:
        raise CalibrationError("give at least one ", FIT, " KEY=LOW:HIGH")
    return bounds


def _read_table(read: Callable[[], Any], what: Keyword) -> Any:
    """A table read by snake-core's ``tables`` (the one parser of targets and logs, under one set of
    limits, as ``snake-cli run`` reads them); its error as a CalibrationError naming the argument."""
    try:
        return read()
    except ValueError as error:
        message = str(error)
        # "targets FILE: ...": the argument named, so that the command can name its flag instead.
        if message.startswith(f"{what.name} "):
            raise CalibrationError(what, message[len(what.name) :]) from None
        raise CalibrationError(message) from None


def read_targets(path: str | os.PathLike, joints: Sequence[str]) -> np.ndarray:
    """The targets CSV as (steps, joints) in the robot's joint order: at most
    ``LIMITS['target_rows']`` rows of finite numbers, read as ``snake-cli run --targets`` reads them
    (snake-core's ``tables``; refused at the first row over, before the rest is read)."""
    return _read_table(lambda: _core.read_targets(os.fspath(path), list(joints)), TARGETS)


def velocity_columns(joints: int) -> list[str]:
    """The optional velocity columns of a log: the base's world-frame linear and angular velocity
    (``getBaseVelocity``) and the joint velocities."""
    return _core.log_columns(joints, True)[len(_core.log_columns(joints, False)) :]


def read_log(path: str | os.PathLike, joints: int, steps: int) -> np.ndarray:
    """The logged trajectory as (steps, 7 + joints): base x, y, z, qx, qy, qz, qw, then the joints;
    (steps, 13 + 2 joints) when the log also holds the velocities (:func:`velocity_columns`, all of
    them after the joints, or none). Row k is step k at ``t`` = k/240 s (within 1 ms), every value at
    most ``LIMITS['position']`` in magnitude; a row past ``steps`` is refused before the rest is read
    (snake-core's ``tables``, the parser of ``snake-cli run``'s logs)."""
    values, _ = _read_table(lambda: _core.read_log(os.fspath(path), joints, steps, DT), LOG)
    return values


def trajectory_error(base: np.ndarray, joints: np.ndarray, log: np.ndarray) -> float:
    """The normalised error of a simulated run against the log (the module's docstring); ``math.inf``
    when it is not finite (a run that blew up, an error that overflows)."""
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is a failed candidate, not a warning
        dp = base[:, :3] - log[:, :3]
        dq = joints - log[:, 7 : 7 + joints.shape[1]]
        value = float(np.mean(np.sum(dp * dp, axis=1)) / POSITION_SCALE**2)
        if dq.size:
            value += float(np.mean(dq * dq) / ANGLE_SCALE**2)
    return value if math.isfinite(value) else math.inf


@dataclass
class Problem:
    """A calibration's inputs, read and checked. ``window``: physics steps per window of the error
    (:mod:`snakesim.runs.calibrate_windows`); 0 (the default) measures the whole run."""

    robot: str
    targets: np.ndarray
    log: np.ndarray
    world: str | None = None
    start: tuple[float, float, float, float] | None = None
    fixed: dict[str, float] = field(default_factory=dict)
    window: int = 0
    states: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.window and self.states is None:
            joints = self.targets.shape[1]
            self.states = window_states(self.log, joints, self.window)

    def simulate(self, values: dict[str, float], whole: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The run with ``values`` (over windows unless ``whole`` or the problem has none)."""
        windows = () if whole or not self.window else (self.window, self.states)
        return _core.simulate_robot(
            self.robot, self.targets, self.world, self.start, json.dumps({**self.fixed, **values}), *windows
        )

    def error(self, values: dict[str, float], whole: bool = False) -> float:
        """The candidate's error (over windows unless ``whole``); ``math.inf`` for one whose simulation
        fails."""
        try:
            base, joints = self.simulate(values, whole)
        except RuntimeError:  # the engine failed (an unstable candidate)
            return math.inf
        return trajectory_error(base, joints, self.log)


def check_bounds(problem: Problem, bounds: dict[str, tuple[float, float]]) -> None:
    """CalibrationError naming the key unless both bounds of every key are values the simulation takes
    (snake-core's ``Overrides::validate``: ``motors.max_velocity`` and ``mass_scale`` above 0, frictions
    up to ``MAX_WORLD_FRICTION``, ...) on this robot (skin friction only where it has skin): one physics
    step at each bound, before any fit, instead of a refused candidate in the middle of it."""
    first = Problem(
        problem.robot, problem.targets[:1], problem.log[:1], problem.world, problem.start, problem.fixed
    )  # one step: no window restarts
    for key, (low, high) in bounds.items():
        for value in (low, high):
            try:
                first.simulate({key: value})
            except ValueError as error:
                raise CalibrationError(FIT, f" {key}={low!r}:{high!r}: {error}") from None
            except RuntimeError:
                pass  # an unstable value is a candidate the fit scores as failed, not bad input


class Space:
    """The fitted keys' bounds and their map to the optimizer's [0, 1] (log where low > 0)."""

    def __init__(self, bounds: dict[str, tuple[float, float]]) -> None:
        self.keys = list(bounds)
        self.bounds = bounds

    def value(self, i: int, u: float) -> float:
        """Key i's value at ``u`` in [0, 1]."""
        low, high = self.bounds[self.keys[i]]
        u = min(max(float(u), 0.0), 1.0)
        if low > 0:
            value = math.exp(math.log(low) + u * (math.log(high) - math.log(low)))
        else:
            value = low + u * (high - low)
        return float(min(max(value, low), high))  # within the checked bounds despite rounding

    def to_values(self, x: np.ndarray) -> dict[str, float]:
        return {key: self.value(i, u) for i, (key, u) in enumerate(zip(self.keys, x))}


def population_size(keys: int) -> int:
    """Candidates per CMA-ES generation when fitting ``keys`` keys (its default, 4 + 3 ln n, and at
    least 8): the fewest simulations a fit makes."""
    return max(8, 4 + int(3 * math.log(keys)))


def check_max_evals(max_evals: int, keys: int) -> None:
    """CalibrationError unless ``max_evals`` holds at least one generation of candidates for ``keys``
    fitted keys, and at most :data:`MAX_EVALS`."""
    population = population_size(keys)
    if max_evals > MAX_EVALS:
        raise CalibrationError(MAX_EVALS_ARG, f" must be at most {MAX_EVALS:,}, got {short_int(max_evals)}")
    if max_evals < population:
        raise CalibrationError(
            MAX_EVALS_ARG,
            f" {short_int(max_evals)} is less than one generation: fitting {keys} key(s) "
            f"simulates {population} candidates a generation; give ",
            MAX_EVALS_ARG,
            f" {population} or more",
        )


def short_int(value: int) -> str:
    """An integer for a message, short whatever its size (``1e+40`` for forty digits)."""
    text = str(value)
    digits = text.lstrip("-")
    return text if len(digits) <= 15 else f"{text[: len(text) - len(digits) + 1]}e+{len(digits) - 1}"


_WORKER: Problem | None = None


def _init_worker(problem: Problem) -> None:
    global _WORKER
    _WORKER = problem
    # Ctrl-C reaches the whole process group: the main process answers it and ends the workers
    # (_stop_workers), which would otherwise each print a traceback.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _worker_error(values: dict[str, float]) -> float:
    assert _WORKER is not None
    return _WORKER.error(values)


def _worker_whole_error(values: dict[str, float]) -> float:
    assert _WORKER is not None
    return _WORKER.error(values, whole=True)


def _stop_workers(pool: concurrent.futures.ProcessPoolExecutor) -> None:
    """Ends the pool's processes now, in the middle of their simulations (after Ctrl-C, SIGTERM or an
    error): ``shutdown()`` alone waits for each to finish its candidate, minutes for a long log."""
    # Python 3.14 has ProcessPoolExecutor.terminate_workers(); before it, the pool's own table.
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        process.terminate()
    for process in processes:
        process.join(5)


def calibrate(
    problem: Problem,
    bounds: dict[str, tuple[float, float]],
    *,
    max_evals: int = 3000,
    workers: int = 1,
    seed: int = 0,
    tolerance: float = 1e-3,
    max_restarts: int = 9,
    progress: Callable[[int, float], None] | None = None,
    error_before: float | None = None,
    with_intervals: bool = True,
    stage: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Fits ``bounds``' keys with IPOP-CMA-ES (:mod:`snakesim.runs.calibrate_search`) on the problem's
    error (over windows when it has them), then measures each key's interval
    (:mod:`snakesim.runs.calibrate_intervals`, unless ``with_intervals`` is False). Returns the JSON
    result (``fitted``, ``intervals``, ``error_before`` (the robot file's own values: ``error_before``
    if given, else simulated; None when not finite), ``error_after``, the whole-run errors before and
    after, ``simulations``, ``restarts``, ``wall_seconds``, ...), whose numbers are all finite.
    CalibrationError when ``max_evals`` is below one generation, or when no candidate gives a finite
    error. ``max_evals`` bounds the search; the intervals and the whole-run errors add their own
    simulations (``interval_simulations``). ``progress(simulations, best error)`` after each
    generation, ``stage(text)`` when the search is over and the intervals begin."""
    check_max_evals(max_evals, len(bounds))
    clock = time.monotonic()
    check_bounds(problem, bounds)
    space = Space(bounds)
    dim = len(space.keys)
    if error_before is None:
        error_before = problem.error({})
    pool = None
    if workers > 1:
        pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_worker,
            initargs=(problem,),
        )

    def evaluate(xs) -> list[float]:
        candidates = [space.to_values(x) for x in xs]
        if pool:
            return list(pool.map(_worker_error, candidates))
        return [problem.error(c) for c in candidates]

    try:
        found = ipop(
            evaluate,
            dim,
            population=population_size(dim),
            max_evals=max_evals,
            seed=seed,
            tolerance=tolerance,
            max_restarts=max_restarts,
            progress=(lambda n, best, run: progress(1 + n, best)) if progress else None,
        )
        if not math.isfinite(found.best_error):
            raise CalibrationError(
                f"no fit: every one of the {found.failed} candidates' simulations failed (the physics blew "
                "up, or the error against the log is not finite); check the log, the targets and the ",
                FIT,
                " bounds",
            )
        fitted = space.to_values(found.best_x)
        ranges, interval_simulations = ({}, 0)
        if with_intervals:
            if stage:
                stage(f"the intervals of {dim} key(s), about {35 * dim} simulations")
            ranges, interval_simulations = intervals(
                evaluate, space.keys, space.value, np.asarray(found.best_x), found.best_error
            )
        whole = [{}, fitted] if problem.window else []
        if pool and whole:
            whole_before, whole_after = pool.map(_worker_whole_error, whole)
        elif whole:
            whole_before, whole_after = (problem.error(v, whole=True) for v in whole)
        else:
            whole_before, whole_after = error_before, found.best_error
    except BaseException:
        if pool:
            _stop_workers(pool)
            pool = None
        raise
    finally:
        if pool:
            pool.shutdown(cancel_futures=True)

    def finite(value: float) -> float | None:
        return value if math.isfinite(value) else None

    return {
        "fitted": fitted,
        "intervals": ranges,
        "error_before": finite(error_before),
        "error_after": found.best_error,
        "whole_run_error_before": finite(whole_before),
        "whole_run_error_after": finite(whole_after),
        "window_seconds": problem.window * WINDOW_DT if problem.window else None,
        "window_steps": problem.window or None,
        "simulations": 1 + found.simulations,
        "interval_simulations": interval_simulations,
        "failed_simulations": found.failed,
        "generations": found.generations,
        "restarts": [
            {
                "population": r.population,
                "simulations": r.simulations,
                "generations": r.generations,
                "best_error": finite(r.best_error),
                "best": space.to_values(np.asarray(r.best_x)) if r.best_x else None,
                "stopped": r.stopped,
            }
            for r in found.runs
        ],
        "stopped": found.stopped,
        "interval_delta": delta_for(found.best_error),
        "wall_seconds": time.monotonic() - clock,
        "bounds": {k: list(v) for k, v in bounds.items()},
        "workers": workers,
        "seed": seed,
        "error": {
            "definition": "mean over steps of |dp|^2/position_scale^2 "
            "+ mean over joints of dq^2/angle_scale^2"
            + (", each window restarted from the logged state" if problem.window else ""),
            "position_scale_m": POSITION_SCALE,
            "angle_scale_rad": ANGLE_SCALE,
        },
        "steps": int(problem.targets.shape[0]),
        "not_in_robot_file": [k for k in fitted if k in NOT_IN_ROBOT_FILE],
    }


def fitted_robot_yaml(robot: str | os.PathLike, fitted: dict[str, float], out: str | os.PathLike) -> str:
    """The robot file ``robot`` with ``fitted`` written in, as YAML text for ``out`` (its ``urdf:``
    path made relative to ``out``'s folder), by snake-core's ``fitted_robot_file``: the mapping the
    simulation applies, so the file builds the fitted robot, per-link values included. Keys a robot
    file cannot hold are comments."""
    robot = Path(robot)
    if robot.suffix.lower() in (".yaml", ".yml"):
        data = json.loads(_core.parse_yaml(read_text(robot, "config_bytes")))
        urdf = robot.parent / data["urdf"]
    else:
        urdf = robot
    relative = os.path.relpath(os.path.realpath(urdf), os.path.realpath(Path(out).parent))
    return _core.fitted_robot_file(str(robot), json.dumps(fitted), relative)


def plot(
    path: str | os.PathLike,
    problem: Problem,
    fitted: dict[str, float],
    image_format: str | None = None,
    errors: tuple[float | None, float | None] | None = None,
) -> None:
    """Logged vs simulated, with the robot file's values and with the fitted ones: the base path from
    above and the first joints, as ``image_format`` (``png``, ``pdf``, ``svg``; default: by the name's
    extension). The log is drawn as thick light lines, the fit dashed and the start dotted over it, the
    legend below the axes, ``errors`` (before, after) in the title. With windows, the simulated runs are
    the windowed ones the error measured (each window restarted from the log)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    before_b, before_q = problem.simulate({})
    after_b, after_q = problem.simulate(fitted)
    log = problem.log
    joints = problem.targets.shape[1]
    shown = min(joints, 4)
    t = np.arange(1, log.shape[0] + 1) / 240.0
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5.6))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    styles = {
        "log": {"ls": "-", "lw": 5, "alpha": 0.3},
        "start": {"ls": ":", "lw": 1.2},
        "fit": {"ls": "--", "lw": 1.4},
    }
    ax.plot(log[:, 0], log[:, 1], color="k", **styles["log"])
    ax.plot(before_b[:, 0], before_b[:, 1], color="k", **styles["start"])
    ax.plot(after_b[:, 0], after_b[:, 1], color="k", **styles["fit"])
    ax.set(xlabel="x (m)", ylabel="y (m)", title="base path (from above)", aspect="equal")
    ax.set_aspect("equal", adjustable="datalim")
    for j in range(shown):
        c = colors[j % len(colors)]
        bx.plot(t, log[:, 7 + j], color=c, **styles["log"])
        bx.plot(t, before_q[:, j], color=c, **styles["start"])
        bx.plot(t, after_q[:, j], color=c, **styles["fit"])
    bx.set(
        xlabel="t (s)", ylabel="joint angle (rad)", title=f"joints q0..q{shown - 1} (of {joints}), by colour"
    )
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color="grey", **styles["log"], label="log"),
        Line2D([], [], color="grey", **styles["start"], label="robot file's values (start)"),
        Line2D([], [], color="grey", **styles["fit"], label="fitted"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=3, frameon=False)
    kind = f"error over {problem.window / 240:g} s windows" if problem.window else "whole-run error"
    if errors is not None:
        before, after = ("failed" if e is None else f"{e:.4g}" for e in errors)
        fig.suptitle(f"{kind}: {before} (robot file) -> {after} (fitted)")
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.savefig(path, dpi=80, format=image_format)
    plt.close(fig)
