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

A candidate whose simulation fails (the engine refuses it, or its error is not finite) scores
``math.inf``: CMA-ES ranks it last, and it is never the fit. A calibration none of whose candidates
gives a finite error is refused (:class:`CalibrationError`), as are inputs beyond the limits of
``snake-cli run --targets`` (``LIMITS['target_rows']`` rows, ``LIMITS['csv_bytes']``) and log values
beyond ``LIMITS['position']``.

Optimizer: CMA-ES (the ``cmaes`` package, bounded) over the fitted keys mapped to [0, 1] (linearly, or
logarithmically where the lower bound is > 0: gains and frictions are scales), each generation's
candidates simulated in parallel processes. Every simulation can be interrupted: Ctrl-C or SIGTERM
ends one in the main process within 20 ms (``_core.simulate_robot``), and ends the worker processes
at once (:func:`_stop_workers`).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import io
import json
import math
import multiprocessing
import os
import signal
import time
from array import array
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from snakesim import _core
from snakesim.files import open_regular, read_text
from snakesim.limits import LIMITS
from snakesim.runs.arguments import ArgumentError, Keyword

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
)
#: Keys a robot file cannot hold: reported in the JSON and as a comment of the fitted robot file.
NOT_IN_ROBOT_FILE = ("ground_friction", "lateral_friction", "mass_scale")
#: Most simulations of one calibration (``max_evals``).
MAX_EVALS = LIMITS["calibration_evals"]
POSITION_SCALE = 0.01  # m
ANGLE_SCALE = 0.001  # rad
BASE_COLUMNS = ("step", "t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw")
#: The physics step, s: a log and its targets have one row per step.
DT = 1.0 / 240.0
#: Most a log's ``t`` may differ from step x DT, s: time stamps written to the millisecond pass; a row a
#: step early or late (4.2 ms) does not.
T_TOLERANCE = 1e-3
#: Longest line of a targets or log CSV, characters (a row of 137 numbers in shortest form is ~3 kB).
LINE_CHARS = 1 << 20
#: What CMA-ES is told of a candidate whose simulation failed (or twice the generation's largest finite
#: error, when that is more), so that it ranks last; the candidate's own error is ``math.inf``.
FAILED = 1e12


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


def excerpt(text: str) -> str:
    """A user's value quoted for a message: at most 24 characters, escaped."""
    return repr(text[:24]) + ("..." if len(text) > 24 else "")


def _numbers(cells: list[str], file: str, line: int, names: Sequence[str], bound: float) -> list[float]:
    """The cells as floats of magnitude at most ``bound`` (any finite value for ``math.inf``)."""
    try:
        values = [float(c) for c in cells]
        if all(math.isfinite(v) and abs(v) <= bound for v in values):
            return values
    except ValueError:
        pass
    for name, cell in zip(names, cells):
        try:
            v = float(cell)
        except ValueError:
            raise CalibrationError(f"{file}:{line}: {name}: {excerpt(cell)} is not a number") from None
        if not math.isfinite(v):
            raise CalibrationError(f"{file}:{line}: {name}: {excerpt(cell)} is not a finite number")
        if abs(v) > bound:
            raise CalibrationError(
                f"{file}:{line}: {name}: {excerpt(cell)} is beyond +-{bound:g} (LIMITS['position'])"
            )
    raise AssertionError("unreachable: some cell was refused")


def _lines(path: str | os.PathLike, what: Keyword) -> Iterator[tuple[int, list[str]]]:
    """(line number, stripped cells) of each non-blank line of a CSV, read a line at a time: a regular
    file of at most ``LIMITS['csv_bytes']``, UTF-8, lines of at most :data:`LINE_CHARS`;
    CalibrationError naming the file (and line) otherwise."""
    file = os.fspath(path)
    try:
        raw = open_regular(path, "csv_bytes")
    except (OSError, ValueError) as error:
        raise CalibrationError(what, f" {file}: {getattr(error, 'strerror', None) or error}") from None
    cap = LIMITS["csv_bytes"]
    with io.TextIOWrapper(raw, encoding="utf-8") as f:
        line, read = 0, 0
        while True:
            try:
                text = f.readline(LINE_CHARS)
            except UnicodeDecodeError as error:
                raise CalibrationError(
                    what, f" {file}: not UTF-8 text ({error.reason}, after line {line})"
                ) from None
            if not text:
                return
            line += 1
            read += len(text)
            if len(text) == LINE_CHARS and not text.endswith("\n"):
                raise CalibrationError(f"{file}:{line}: a line longer than {LINE_CHARS:,} characters")
            if read > cap:  # the file grew while read
                raise CalibrationError(f"{what} {file}: more than {cap:,} bytes (LIMITS['csv_bytes'])")
            if text.strip():
                yield line, [c.strip() for c in text.split(",")]


def _header(lines: Iterator[tuple[int, list[str]]], file: str) -> tuple[int, list[str]]:
    first = next(lines, None)
    if first is None:
        raise CalibrationError(f"{file}: empty; expected a header")
    return first


def _row(file: str, line: int, cells: list[str], header: list[str], k: int) -> None:
    """Row ``k`` (from 1) has the header's cells and step ``k``."""
    if len(cells) != len(header):
        raise CalibrationError(f"{file}:{line}: {len(cells)} cells, the header has {len(header)}")
    if cells[0] != str(k):
        raise CalibrationError(
            f"{file}:{line}: step {excerpt(cells[0])}, expected {k} "
            "(rows sorted, one per physics step, from 1)"
        )


def read_targets(path: str | os.PathLike, joints: Sequence[str]) -> np.ndarray:
    """The targets CSV as (steps, joints) in the robot's joint order: at most
    ``LIMITS['target_rows']`` rows of finite numbers, as ``snake-cli run --targets`` reads them
    (refused at the first row over, before the rest is read)."""
    file = os.fspath(path)
    cap = LIMITS["target_rows"]
    values = array("d")
    with contextlib.closing(_lines(path, TARGETS)) as lines:
        first, header = _header(lines, file)
        if header[0] != "step":
            raise CalibrationError(f"{file}:{first}: the first column must be 'step'")
        names = header[1:]
        for n in names:
            if n not in joints:
                raise CalibrationError(
                    f"{file}:{first}: column {excerpt(n)} is not a movable joint of the robot"
                )
        if sorted(names) != sorted(joints):
            missing = [j for j in joints if j not in names]
            raise CalibrationError(
                f"{file}:{first}: no column (or two) for joint(s) {', '.join(missing) or names}"
            )
        k = 0
        for line, cells in lines:
            k += 1
            if k > cap:
                raise CalibrationError(
                    f"{file}:{line}: more than {cap:,} rows (LIMITS['target_rows']: an hour of 1/240 s "
                    "steps, as snake-cli run --targets)"
                )
            _row(file, line, cells, header, k)
            values.extend(_numbers(cells[1:], file, line, names, math.inf))
    if k == 0:
        raise CalibrationError(f"{file}: no rows after the header")
    data = np.frombuffer(values, dtype=np.float64).reshape(k, len(names))
    order = [names.index(j) for j in joints]
    return np.ascontiguousarray(data[:, order])


def read_log(path: str | os.PathLike, joints: int, steps: int) -> np.ndarray:
    """The logged trajectory as (steps, 7 + joints): base x, y, z, qx, qy, qz, qw, then the joints.
    Row k is step k at ``t`` = k/240 s (within :data:`T_TOLERANCE`), every value at most
    ``LIMITS['position']`` in magnitude; a row past ``steps`` is refused before the rest is read."""
    file = os.fspath(path)
    bound = float(LIMITS["position"])
    values = array("d")
    expected = [*BASE_COLUMNS, *(f"q{j}" for j in range(joints))]
    with contextlib.closing(_lines(path, LOG)) as lines:
        first, header = _header(lines, file)
        if header != expected:
            q = sum(1 for h in header if h.startswith("q") and h[1:].isdigit())
            if header[: len(BASE_COLUMNS)] == list(BASE_COLUMNS) and q != joints:
                raise CalibrationError(
                    f"{file}:{first}: {q} joint columns, the robot has {joints} movable joints"
                )
            raise CalibrationError(
                f"{file}:{first}: expected the header {','.join(expected[:10])},... (snake-cli run --output)"
            )
        names = header[2:]
        k = 0
        for line, cells in lines:
            k += 1
            if k > steps:
                raise CalibrationError(
                    f"{file}:{line}: more than {steps} rows, the targets have {steps} (one per physics step)"
                )
            _row(file, line, cells, header, k)
            try:
                t = float(cells[1])
            except ValueError:
                raise CalibrationError(f"{file}:{line}: t: {excerpt(cells[1])} is not a number") from None
            if not abs(t - k * DT) <= T_TOLERANCE:
                raise CalibrationError(
                    f"{file}:{line}: t: {excerpt(cells[1])}, expected step {k} x 1/240 s = {k * DT:.6g} s "
                    "(one row per physics step, t = 0 at the first command)"
                )
            values.extend(_numbers(cells[2:], file, line, names, bound))
    if k != steps:
        raise CalibrationError(f"{file}: {k} rows, the targets have {steps} (one per physics step)")
    return np.frombuffer(values, dtype=np.float64).reshape(k, len(names))


def trajectory_error(base: np.ndarray, joints: np.ndarray, log: np.ndarray) -> float:
    """The normalised error of a simulated run against the log (the module's docstring); ``math.inf``
    when it is not finite (a run that blew up, an error that overflows)."""
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is a failed candidate, not a warning
        dp = base[:, :3] - log[:, :3]
        dq = joints - log[:, 7:]
        value = float(np.mean(np.sum(dp * dp, axis=1)) / POSITION_SCALE**2)
        if dq.size:
            value += float(np.mean(dq * dq) / ANGLE_SCALE**2)
    return value if math.isfinite(value) else math.inf


@dataclass
class Problem:
    """A calibration's inputs, read and checked."""

    robot: str
    targets: np.ndarray
    log: np.ndarray
    world: str | None = None
    start: tuple[float, float, float, float] | None = None
    fixed: dict[str, float] = field(default_factory=dict)

    def simulate(self, values: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
        return _core.simulate_robot(
            self.robot, self.targets, self.world, self.start, json.dumps({**self.fixed, **values})
        )

    def error(self, values: dict[str, float]) -> float:
        """The candidate's error; ``math.inf`` for one whose simulation fails."""
        try:
            base, joints = self.simulate(values)
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
    )
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

    def to_values(self, x: np.ndarray) -> dict[str, float]:
        out = {}
        for key, u in zip(self.keys, np.clip(x, 0.0, 1.0)):
            low, high = self.bounds[key]
            if low > 0:
                value = math.exp(math.log(low) + u * (math.log(high) - math.log(low)))
            else:
                value = low + u * (high - low)
            out[key] = float(min(max(value, low), high))  # within the checked bounds despite rounding
        return out


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
    max_evals: int = 600,
    workers: int = 1,
    seed: int = 0,
    tolerance: float = 1e-3,
    progress: Callable[[int, float], None] | None = None,
    error_before: float | None = None,
) -> dict[str, Any]:
    """Fits ``bounds``' keys with CMA-ES; returns the JSON result (``fitted``, ``error_before`` (the
    robot file's own values: ``error_before`` if given, else simulated; None when not finite),
    ``error_after``, ``simulations``, ``failed_simulations``, ``wall_seconds``, ``bounds``, ...), whose
    numbers are all finite. CalibrationError when ``max_evals`` is below one generation, or when no
    candidate gives a finite error."""
    from cmaes import CMA

    check_max_evals(max_evals, len(bounds))
    clock = time.monotonic()
    check_bounds(problem, bounds)
    space = Space(bounds)
    dim = len(space.keys)
    optimizer = CMA(
        mean=np.full(dim, 0.5),
        sigma=0.3,
        bounds=np.array([[0.0, 1.0]] * dim),
        seed=seed,
        population_size=population_size(dim),
    )
    if error_before is None:
        error_before = problem.error({})
    simulations, failed = 1, 0
    best_x, best_error = np.full(dim, 0.5), math.inf
    generations = 0
    pool = None
    if workers > 1:
        pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_worker,
            initargs=(problem,),
        )
    try:
        while simulations < max_evals + 1:
            n = min(optimizer.population_size, max_evals + 1 - simulations)
            if n < optimizer.population_size:
                break  # a partial generation cannot be told to CMA-ES
            xs = [optimizer.ask() for _ in range(n)]
            candidates = [space.to_values(x) for x in xs]
            errors = (
                list(pool.map(_worker_error, candidates)) if pool else [problem.error(c) for c in candidates]
            )
            simulations += n
            generations += 1
            finite = [e for e in errors if math.isfinite(e)]
            failed += n - len(finite)
            # A failed candidate ranks last; its error is never the fit's.
            last = min(max([FAILED, *(2 * e for e in finite)]), np.finfo(np.float64).max)
            optimizer.tell([(x, e if math.isfinite(e) else last) for x, e in zip(xs, errors)])
            if finite:
                k = int(np.argmin(errors))
                if errors[k] < best_error:
                    best_x, best_error = xs[k], errors[k]
            if progress:
                progress(simulations, best_error)
            # Converged: the generation's candidates all lie within `tolerance` (of [0, 1]) of each other.
            spread = float(np.max(np.ptp(np.array(xs), axis=0)))
            if optimizer.should_stop() or spread < tolerance:
                break
    except BaseException:
        if pool:
            _stop_workers(pool)
            pool = None
        raise
    finally:
        if pool:
            pool.shutdown(cancel_futures=True)
    if not math.isfinite(best_error):
        raise CalibrationError(
            f"no fit: every one of the {failed} candidates' simulations failed (the physics blew up, or "
            "the error against the log is not finite); check the log, the targets and the ",
            FIT,
            " bounds",
        )
    fitted = space.to_values(best_x)
    return {
        "fitted": fitted,
        "error_before": error_before if math.isfinite(error_before) else None,
        "error_after": best_error,
        "simulations": simulations,
        "failed_simulations": failed,
        "generations": generations,
        "wall_seconds": time.monotonic() - clock,
        "bounds": {k: list(v) for k, v in bounds.items()},
        "workers": workers,
        "seed": seed,
        "error": {
            "definition": "mean over steps of |dp|^2/position_scale^2 "
            "+ mean over joints of dq^2/angle_scale^2",
            "position_scale_m": POSITION_SCALE,
            "angle_scale_rad": ANGLE_SCALE,
        },
        "steps": int(problem.targets.shape[0]),
        "not_in_robot_file": [k for k in fitted if k in NOT_IN_ROBOT_FILE],
    }


def _yaml_value(v: Any) -> str:
    return json.dumps(v)  # JSON is YAML's flow style


def fitted_robot_yaml(robot: str | os.PathLike, fitted: dict[str, float], out: str | os.PathLike) -> str:
    """The robot file ``robot`` with ``fitted`` written in, as YAML text for ``out`` (its ``urdf:``
    path made relative to ``out``'s folder). Keys a robot file cannot hold are comments."""
    robot = Path(robot)
    if robot.suffix.lower() in (".yaml", ".yml"):
        data = json.loads(_core.parse_yaml(read_text(robot, "config_bytes")))
        urdf = robot.parent / data["urdf"]
    else:
        data, urdf = {}, robot
    data["urdf"] = os.path.relpath(os.path.realpath(urdf), os.path.realpath(Path(out).parent))
    motors = dict(data.get("motors") or {})
    for key in ("kp", "kd", "max_velocity"):
        if f"motors.{key}" in fitted:
            motors[key] = fitted[f"motors.{key}"]
    if "motors.max_velocity" in fitted:
        for settings in (data.get("joints") or {}).values():
            if isinstance(settings, dict):
                settings.pop("max_velocity", None)
    if motors:
        data["motors"] = motors
    axes = [fitted.get(f"anisotropic_friction.{a}") for a in "xyz"]
    if any(v is not None for v in axes):
        old = data.get("anisotropic_friction") or [1.0, 1.0, 1.0]
        data["anisotropic_friction"] = [o if v is None else v for o, v in zip(old, axes)]
    skin = {
        k: fitted[f"skin_friction.{k}"]
        for k in ("forward", "backward", "transverse")
        if f"skin_friction.{k}" in fitted
    }
    if skin:
        if data.get("skin_friction"):
            data["skin_friction"] = {**data["skin_friction"], **skin}
        for settings in (data.get("links") or {}).values():
            if isinstance(settings, dict) and settings.get("skin_friction"):
                settings["skin_friction"] = {**settings["skin_friction"], **skin}
    lines = [f"# {robot.name} with values fitted by snakesim calibrate (docs/calibration.md)."]
    for key in NOT_IN_ROBOT_FILE:
        if key in fitted:
            where = "a world file's ground_friction" if key == "ground_friction" else "no robot-file key"
            lines.append(f"# fitted {key}: {fitted[key]!r} ({where}; not applied by this file)")
    lines += [f"{k}: {_yaml_value(v)}" for k, v in data.items()]
    return "\n".join(lines) + "\n"


def plot(
    path: str | os.PathLike, problem: Problem, fitted: dict[str, float], image_format: str | None = None
) -> None:
    """Logged vs simulated (before and after the fit): the base path from above and every joint, as
    ``image_format`` (``png``, ``pdf``, ``svg``; default: by the name's extension)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    before_b, before_q = problem.simulate({})
    after_b, after_q = problem.simulate(fitted)
    log = problem.log
    joints = log.shape[1] - 7
    t = np.arange(1, log.shape[0] + 1) / 240.0
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5))
    ax.plot(log[:, 0], log[:, 1], "k-", lw=2, label="log")
    ax.plot(before_b[:, 0], before_b[:, 1], ":", label="robot file")
    ax.plot(after_b[:, 0], after_b[:, 1], "--", label="fitted")
    ax.set(xlabel="x (m)", ylabel="y (m)", title="base path", aspect="equal")
    ax.legend()
    for j in range(min(joints, 4)):
        (line,) = bx.plot(t, log[:, 7 + j], "-", lw=2, label=f"q{j} log")
        bx.plot(t, after_q[:, j], "--", color=line.get_color(), label=f"q{j} fitted")
    bx.set(xlabel="t (s)", ylabel="joint angle (rad)", title=f"joints (first {min(joints, 4)} of {joints})")
    bx.legend(fontsize="small", ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=100, format=image_format)
    plt.close(fig)
