"""``snakesim calibrate``: fit a robot file's physics to a logged run (docs/calibration.md)."""

from __future__ import annotations

import argparse
import contextlib
import errno
import fcntl
import json
import math
import os
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from snakesim.cli.args import progress_options
from snakesim.cli.errors import UserError, check_distinct, check_writable
from snakesim.files import output_kind
from snakesim.limits import LIMITS
from snakesim.runs.progress import Progress

#: The flags that give ``snakesim.runs.calibrate``'s arguments: its errors name the arguments, the
#: command its flags.
CALIBRATE_FLAGS = {"fit": "--fit", "max_evals": "--max-evals", "targets": "--targets", "log": "--log"}

#: The figure formats of ``--plot``, by the name's extension (as ``snakesim plot``).
PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def _start(text: str) -> tuple[float, float, float, float]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:24]!r} is not X,Y,Z,YAW numbers") from None
    if len(values) != 4 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"{text[:24]!r}: expected four finite numbers X,Y,Z,YAW")
    return values  # type: ignore[return-value]


def _integer(text: str) -> int:
    """An argparse type: an integer (underscores allowed), quoted short when it is not one."""
    try:
        return int(text.replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text[:24]!r}") from None


@dataclass
class _Output:
    path: str | os.PathLike  # as given
    flag: str
    real: Path  # what gets written: a symlink's target
    fd: int | None = None  # a character device or FIFO, opened when checked, written through
    tmp: str | None = None  # the rendered content
    existed: bool = False

    @property
    def label(self) -> str:
        return f"{self.flag} {os.fspath(self.path)}"


class _Outputs(contextlib.AbstractContextManager):
    """The command's outputs, checked before anything is simulated and written only once every one is
    rendered, as nearly all-or-nothing as files allow.

    Checked: as every command checks them (:func:`check_writable`, :func:`check_distinct`: not one of
    the files read, not a directory, ...), and a character device or FIFO is opened for writing at
    once, so a FIFO that nobody reads is refused before the fit (and one that has a reader keeps it).
    Rendered (:meth:`render`): into a temporary file, beside a regular file's target or in a private
    folder for a device or FIFO. Put in place (:meth:`commit`): the devices and FIFOs first (a failed
    write there, ``/dev/full``, replaces no file), then the files renamed over their targets; when a
    rename fails, the files already replaced get their old content back. On leaving, every temporary
    file is removed and every device closed.
    """

    def __init__(self, outputs: list[tuple[str | os.PathLike, str]], inputs: Iterable[str | os.PathLike]):
        inputs = list(inputs)
        for path, flag in outputs:
            check_writable(path, flag, inputs)
        check_distinct(outputs)
        self.items: list[_Output] = []
        self.scratch = tempfile.TemporaryDirectory(prefix="snakesim-out-")
        try:
            for path, flag in outputs:
                item = _Output(path, flag, Path(os.path.realpath(path)))
                if output_kind(item.real) in ("device", "fifo"):
                    item.fd = _open_through(item)
                self.items.append(item)
        except BaseException:
            self.__exit__(None, None, None)
            raise

    def __exit__(self, *exc) -> None:
        for item in self.items:
            if item.fd is not None:
                os.close(item.fd)
                item.fd = None
            if item.tmp is not None and os.path.lexists(item.tmp):  # not put in place
                with contextlib.suppress(OSError):
                    os.unlink(item.tmp)
        self.scratch.cleanup()

    def render(self, flag: str, write: Callable[[str], object]) -> None:
        """Calls ``write(tmp)`` for the output of ``flag``: a temporary file whose name ends as the
        output's does."""
        (item,) = (i for i in self.items if i.flag == flag)
        if item.fd is not None:
            item.tmp = os.path.join(self.scratch.name, f"{flag.lstrip('-')}{item.real.suffix}")
        else:
            fd, item.tmp = tempfile.mkstemp(
                dir=item.real.parent, prefix=f".{item.real.name}.", suffix=item.real.suffix
            )
            os.close(fd)
            umask = os.umask(0)  # mkstemp's file is private (0600): give it a new file's permissions
            os.umask(umask)
            os.chmod(item.tmp, 0o666 & ~umask)
        write(item.tmp)

    def commit(self) -> None:
        through = [i for i in self.items if i.fd is not None]
        files = [i for i in self.items if i.fd is None]
        for item in through:
            assert item.tmp is not None and item.fd is not None
            try:
                with open(item.tmp, "rb") as f, os.fdopen(os.dup(item.fd), "wb", buffering=0) as out:
                    shutil.copyfileobj(f, out)
            except BrokenPipeError:
                raise UserError(f"cannot write {item.label}: its reader went away") from None
            except OSError as error:
                raise UserError(f"cannot write {item.label}: {error.strerror or error}") from None
        done: list[tuple[_Output, str | None]] = []
        try:
            for item in files:
                assert item.tmp is not None
                backup = None
                if os.path.lexists(item.real):
                    item.existed = True
                    with contextlib.suppress(OSError):  # no hard links here: it cannot be put back
                        os.link(item.real, item.tmp + ".old")
                        backup = item.tmp + ".old"
                try:
                    os.replace(item.tmp, item.real)
                except OSError as error:
                    raise UserError(f"cannot write {item.label}: {error.strerror or error}") from None
                done.append((item, backup))
        except BaseException:
            for item, backup in reversed(done):
                with contextlib.suppress(OSError):
                    if backup is not None:
                        os.replace(backup, item.real)
                    elif not item.existed:
                        os.unlink(item.real)
            raise
        finally:
            for _, backup in done:
                if backup is not None and os.path.lexists(backup):
                    os.unlink(backup)


def _open_through(item: _Output) -> int:
    """A character device or FIFO output opened for writing (blocking), or UserError: a FIFO that
    nobody reads is refused rather than waited on."""
    try:
        fd = os.open(item.real, os.O_WRONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as error:
        if error.errno == errno.ENXIO:
            raise UserError(f"cannot write {item.label}: a FIFO that nobody reads") from None
        raise UserError(f"cannot write {item.label}: {error.strerror or error}") from None
    fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
    return fd


def _g(value: float | None) -> str:
    return "failed" if value is None else f"{value:.6g}"


def _seconds(text: str) -> float:
    """An argparse type: a finite number of seconds >= 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds, got {text[:24]!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected finite seconds >= 0, got {text[:24]!r}")
    return value


def _check_window(seconds: float, steps: int, log: str) -> int:
    """--window in physics steps: 0 (the whole run), or at least one step and no longer than the log."""
    from snakesim.runs.calibrate_windows import DT, window_steps

    if seconds == 0:
        return 0
    if seconds < DT * (1 - 1e-9):
        raise UserError(
            f"--window {seconds:g}: shorter than one physics step (1/240 s = {DT:.6g} s); give 0 for the "
            "whole-run error"
        )
    if seconds > steps * DT * (1 + 1e-9):
        raise UserError(
            f"--window {seconds:g}: longer than --log {log} ({steps} steps, {steps * DT:.6g} s); give at "
            "most the log's length, or 0 for the whole-run error"
        )
    return window_steps(seconds)


def _interval_text(entry: dict) -> str:
    if not entry["identifiable"]:
        return f"  [{entry['low']:.6g}, {entry['high']:.6g}]  {entry['reason']}"
    return f"  [{entry['low']:.6g}, {entry['high']:.6g}]"


def cmd_design(args: argparse.Namespace) -> int:
    """--design-targets: writes the designed targets for the robot, nothing else."""
    from snakesim import _core
    from snakesim.runs.calibrate_design import design_targets, targets_csv
    from snakesim.runs.calibrate_windows import DT

    seconds = args.seconds
    rows = LIMITS["target_rows"]
    if not DT <= seconds <= rows * DT:
        raise UserError(
            f"--seconds must be in [{DT:.6g}, {rows * DT:g}] (LIMITS['target_rows'] steps), got {seconds:g}"
        )
    try:
        names = _core.robot_joint_names(str(args.robot))
        inputs = _core.robot_files(str(args.robot))
    except (ValueError, RuntimeError, OSError) as error:
        raise UserError(f"--robot {args.robot}: {error}") from None
    with _Outputs([(args.design_targets, "--design-targets")], inputs) as out:
        text = targets_csv(names, design_targets(len(names), seconds))
        out.render("--design-targets", lambda tmp: Path(tmp).write_text(text))
        out.commit()
    print(
        f"wrote {args.design_targets}: {round(seconds / DT)} steps of {len(names)} joints (steps, a sweep, "
        "an undulation; docs/calibration.md)"
    )
    return 0


def cmd_calibrate(args: argparse.Namespace) -> int:
    if args.design_targets is not None:
        return cmd_design(args)
    missing = [
        f
        for f, v in (
            ("--targets", args.targets),
            ("--log", args.log),
            ("--fit", args.fit),
            ("--out", args.out),
        )
        if not v
    ]
    if missing:
        raise UserError(f"the following arguments are required: {', '.join(missing)} (or --design-targets)")
    from snakesim import _core
    from snakesim.runs.calibrate import (
        CalibrationError,
        Problem,
        calibrate,
        check_max_evals,
        fitted_robot_yaml,
        parse_fit,
        read_log,
        read_targets,
        short_int,
        trajectory_error,
    )
    from snakesim.runs.calibrate import plot as draw

    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    most = LIMITS["calibration_workers"]
    if not 1 <= workers <= most:
        raise UserError(f"--workers must be in [1, {most}], got {short_int(workers)}")
    if not 0 <= args.seed <= LIMITS["seed"]:
        raise UserError(f"--seed must be in [0, {LIMITS['seed']}], got {short_int(args.seed)}")
    image_format = None
    if args.plot is not None:
        suffix = Path(args.plot).suffix.lower()
        if suffix not in PLOT_SUFFIXES:
            raise UserError(
                f"cannot write --plot {args.plot}: expected a {', '.join(PLOT_SUFFIXES[:-1])} or "
                f"{PLOT_SUFFIXES[-1]} file (the format is the name's extension)"
            )
        image_format = suffix[1:]
    outputs: list[tuple[str | os.PathLike, str]] = [(args.out, "--out")]
    if args.json not in (None, "-"):
        outputs.append((args.json, "--json"))
    if args.plot is not None:
        outputs.append((args.plot, "--plot"))
    try:
        bounds = parse_fit(args.fit)
        check_max_evals(args.max_evals, len(bounds))
        # The robot and the world first: the files they read (the URDF a robot file names, a world's
        # heightfield) are inputs that no output may replace.
        try:
            joints = _core.robot_joint_names(str(args.robot))
            inputs = [*_core.robot_files(str(args.robot)), args.targets, args.log]
        except (ValueError, RuntimeError, OSError) as error:
            raise CalibrationError(f"--robot {args.robot}: {error}") from None
        if args.world is not None:
            try:
                inputs += _core.world_files(str(args.world))
            except (ValueError, RuntimeError, OSError) as error:
                raise CalibrationError(f"--world {args.world}: {error}") from None
    except CalibrationError as error:
        raise UserError(error.naming(CALIBRATE_FLAGS)) from None
    with _Outputs(outputs, inputs) as out:
        try:
            targets = read_targets(args.targets, joints)
            log = read_log(args.log, len(joints), targets.shape[0])
            problem = Problem(
                robot=str(args.robot),
                targets=targets,
                log=log,
                world=None if args.world is None else str(args.world),
                start=args.start,
                window=_check_window(args.window, targets.shape[0], args.log),
            )
            try:
                # The robot, the world and the start build, before any fit: the robot file's own error.
                before = trajectory_error(*problem.simulate({}), problem.log)
            except (ValueError, RuntimeError) as error:
                raise CalibrationError(f"--robot {args.robot}: {error}") from None
            # On stderr, one step per generation of CMA-ES: the fit's simulations (the robot file's
            # own, `before`, not counted) of at most --max-evals, and the best error so far; then the
            # intervals' simulations, on a line of their own.
            with Progress(args.max_evals, "simulations", "calibrate", args.progress) as shown:
                result = calibrate(
                    problem,
                    bounds,
                    max_evals=args.max_evals,
                    workers=workers,
                    seed=args.seed,
                    progress=lambda simulations, best: shown.update(
                        simulations - 1, f"best error {_g(best) if math.isfinite(best) else '-'}"
                    ),
                    error_before=before,
                    # A line of its own (none with --no-progress): the search's count does not hold it.
                    stage=(lambda text: shown.write(f"calibrate: {text}")) if shown.mode != "none" else None,
                )
            yaml_text = fitted_robot_yaml(args.robot, result["fitted"], args.out)
        except CalibrationError as error:
            raise UserError(error.naming(CALIBRATE_FLAGS)) from None
        result.update(robot=str(args.robot), targets=str(args.targets), log=str(args.log), world=args.world)
        text = json.dumps(result, indent=2, allow_nan=False) + "\n"
        try:
            out.render("--out", lambda tmp: Path(tmp).write_text(yaml_text))
            if args.json not in (None, "-"):
                out.render("--json", lambda tmp: Path(tmp).write_text(text))
            if args.plot is not None:
                errors = (result["error_before"], result["error_after"])
                out.render("--plot", lambda tmp: draw(tmp, problem, result["fitted"], image_format, errors))
        except OSError as error:
            raise UserError(f"cannot write {error.filename}: {error.strerror or error}") from None
        out.commit()
    if args.json == "-":
        sys.stdout.write(text)
        return 0
    for key, value in result["fitted"].items():
        interval = _interval_text(result["intervals"][key]) if key in result["intervals"] else ""
        print(f"{key} = {value:.6g}{interval}")
    window = result["window_seconds"]
    kind = f"error over {window:g} s windows" if window else "whole-run error"
    print(
        f"{kind} {_g(result['error_before'])} -> {_g(result['error_after'])}"
        + (
            f"; whole-run error {_g(result['whole_run_error_before'])} -> "
            f"{_g(result['whole_run_error_after'])}"
            if window
            else ""
        )
    )
    print(
        f"{result['simulations']} simulations in {len(result['restarts'])} run(s) of CMA-ES (stopped: "
        f"{result['stopped']}), {result['interval_simulations']} for the intervals, "
        f"{result['wall_seconds']:.1f} s ({workers} workers)"
    )
    print(f"wrote {args.out}" + "".join(f", {p}" for p in (args.json, args.plot) if p is not None))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser(
        "calibrate",
        help="fit a robot file's physics (motor gains, velocity limit, friction, masses) to a logged run",
        description="Fit named physics parameters of a robot file so that the simulated run of its joint "
        "targets reproduces a logged run (a trajectory CSV as snake-cli run --output writes it), with "
        "IPOP-CMA-ES over the given bounds and an error over short windows, each restarted from the "
        "logged state, simulations spread over processes; each fitted value gets an interval, or 'not "
        "identifiable from this log'. Writes the robot file with the "
        "fitted values (--out), the result as JSON and a figure of the logged and simulated path and "
        "joints (docs/calibration.md).",
    )
    p.add_argument("--robot", required=True, metavar="R", help="the robot file (.yaml) or URDF")
    p.add_argument("--targets", metavar="T.csv", help="the joint targets that drove the log (required)")
    p.add_argument("--log", metavar="L.csv", help="the logged trajectory (snake-cli run's CSV; required)")
    p.add_argument("--world", metavar="W", help="a world file (default: the flat plane)")
    p.add_argument(
        "--start", type=_start, metavar="X,Y,Z,YAW", help="start pose of the base (default: the robot file's)"
    )
    p.add_argument(
        "--fit",
        action="append",
        metavar="KEY=LOW:HIGH",
        help="a parameter to fit and its bounds (required), repeatable: motors.kp, motors.kd, "
        "motors.max_velocity, ground_friction, lateral_friction, anisotropic_friction.x|y|z, "
        "skin_friction.forward|backward|transverse, mass_scale, "
        "water.skin_friction|drag|added_mass|added_inertia|linear (a world with water)",
    )
    p.add_argument("--out", metavar="FITTED.yaml", help="the fitted robot file to write (required)")
    p.add_argument("--json", metavar="PATH", help="also write the result as JSON (- : print only JSON)")
    p.add_argument("--plot", metavar="PNG", help="a figure of the logged vs simulated path and joints")
    p.add_argument("--seed", type=_integer, default=0, help="the search's seed")
    p.add_argument(
        "--max-evals",
        "--budget",
        dest="max_evals",
        type=_integer,
        default=3000,
        help="most simulations of the search (IPOP-CMA-ES: restarts with doubled populations until "
        "two runs agree or this is spent); the intervals add about 35 per fitted key",
    )
    p.add_argument(
        "--window",
        type=_seconds,
        default=0.25,
        metavar="SECONDS",
        help="the error over windows of this length, each restarted from the logged state (multiple "
        "shooting); 0: over the whole run",
    )
    p.add_argument(
        "--design-targets",
        metavar="T.csv",
        help="instead of fitting, write joint targets that excite the fitted parameters (steps, a "
        "sweep, an undulation) for --robot, to run and log on the robot before calibrating",
    )
    p.add_argument(
        "--seconds", type=_seconds, default=8.0, help="length of --design-targets' targets (default 8)"
    )
    p.add_argument("--workers", type=_integer, help="processes that simulate (default: the number of cores)")
    progress_options(p, "generation of simulations")
    p.set_defaults(func=cmd_calibrate)
