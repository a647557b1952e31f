"""``snakesim calibrate``: fit a robot file's physics to a logged run (docs/calibration.md)."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

from snakesim.cli.errors import UserError, check_distinct, check_writable
from snakesim.files import write_atomically


def _start(text: str) -> tuple[float, float, float, float]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not X,Y,Z,YAW numbers") from None
    if len(values) != 4 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: expected four finite numbers X,Y,Z,YAW")
    return values  # type: ignore[return-value]


def cmd_calibrate(args: argparse.Namespace) -> int:
    from snakesim import _core
    from snakesim.runs.calibrate import (
        MAX_EVALS,
        CalibrationError,
        Problem,
        calibrate,
        fitted_robot_yaml,
        parse_fit,
        read_log,
        read_targets,
    )
    from snakesim.runs.calibrate import plot as draw

    inputs = [p for p in (args.robot, args.targets, args.log, args.world) if p is not None]
    outputs: list[tuple[str | Path, str]] = [(args.out, "--out")]
    if args.json not in (None, "-"):
        outputs.append((args.json, "--json"))
    if args.plot is not None:
        outputs.append((args.plot, "--plot"))
    for path, flag in outputs:
        check_writable(path, flag, inputs)
    check_distinct(outputs)
    if not 1 <= args.max_evals <= MAX_EVALS:
        raise UserError(f"--max-evals must be in [1, {MAX_EVALS}], got {args.max_evals}")
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    if not 1 <= workers <= 256:
        raise UserError(f"--workers must be in [1, 256], got {workers}")
    try:
        bounds = parse_fit(args.fit)
        try:
            joints = _core.robot_joint_names(str(args.robot))
        except (ValueError, RuntimeError, OSError) as error:
            raise CalibrationError(f"--robot {args.robot}: {error}") from None
        targets = read_targets(args.targets, joints)
        log = read_log(args.log, len(joints), targets.shape[0])
        problem = Problem(
            robot=str(args.robot),
            targets=targets,
            log=log,
            world=None if args.world is None else str(args.world),
            start=args.start,
        )
        try:
            problem.simulate({})  # the robot, the world and the start build, before any fit
        except (ValueError, RuntimeError) as error:
            raise CalibrationError(f"--robot {args.robot}: {error}") from None
        quiet = args.json == "-"

        def progress(simulations: int, best: float) -> None:
            if not quiet:
                print(f"\r{simulations} simulations, best error {best:.6g}", end="", flush=True)

        result = calibrate(
            problem, bounds, max_evals=args.max_evals, workers=workers, seed=args.seed, progress=progress
        )
        if not quiet:
            print()
        yaml_text = fitted_robot_yaml(args.robot, result["fitted"], args.out)
    except CalibrationError as error:
        raise UserError(str(error)) from None
    result.update(robot=str(args.robot), targets=str(args.targets), log=str(args.log), world=args.world)
    text = json.dumps(result, indent=2) + "\n"
    try:
        write_atomically(args.out, lambda tmp: Path(tmp).write_text(yaml_text))
        if args.json not in (None, "-"):
            write_atomically(args.json, lambda tmp: Path(tmp).write_text(text))
        if args.plot is not None:
            write_atomically(args.plot, lambda tmp: draw(tmp, problem, result["fitted"]))
    except OSError as error:
        raise UserError(f"cannot write {error.filename}: {error.strerror or error}") from None
    if args.json == "-":
        sys.stdout.write(text)
        return 0
    for key, value in result["fitted"].items():
        print(f"{key} = {value:.6g}")
    print(
        f"error {result['error_before']:.6g} -> {result['error_after']:.6g} in {result['simulations']} "
        f"simulations, {result['wall_seconds']:.1f} s ({workers} workers)"
    )
    print(f"wrote {args.out}" + "".join(f", {p}" for p in (args.json, args.plot) if p is not None))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser(
        "calibrate",
        help="fit a robot file's physics (motor gains, velocity limit, friction, masses) to a logged run",
        description="Fit named physics parameters of a robot file so that the simulated run of its joint "
        "targets reproduces a logged run (a trajectory CSV as snake-cli run --output writes it), with "
        "CMA-ES over the given bounds, simulations spread over processes. Writes the robot file with the "
        "fitted values (--out), the result as JSON and a figure of the logged and simulated path and "
        "joints (docs/calibration.md).",
    )
    p.add_argument("--robot", required=True, metavar="R", help="the robot file (.yaml) or URDF")
    p.add_argument("--targets", required=True, metavar="T.csv", help="the joint targets that drove the log")
    p.add_argument(
        "--log", required=True, metavar="L.csv", help="the logged trajectory (snake-cli run's CSV)"
    )
    p.add_argument("--world", metavar="W", help="a world file (default: the flat plane)")
    p.add_argument(
        "--start", type=_start, metavar="X,Y,Z,YAW", help="start pose of the base (default: the robot file's)"
    )
    p.add_argument(
        "--fit",
        action="append",
        required=True,
        metavar="KEY=LOW:HIGH",
        help="a parameter to fit and its bounds, repeatable: motors.kp, motors.kd, motors.max_velocity, "
        "ground_friction, lateral_friction, anisotropic_friction.x|y|z, skin_friction.forward|backward|"
        "transverse, mass_scale",
    )
    p.add_argument("--out", required=True, metavar="FITTED.yaml", help="the fitted robot file to write")
    p.add_argument("--json", metavar="PATH", help="also write the result as JSON (- : print only JSON)")
    p.add_argument("--plot", metavar="PNG", help="a figure of the logged vs simulated path and joints")
    p.add_argument("--seed", type=int, default=0, help="CMA-ES's seed")
    p.add_argument(
        "--max-evals", "--budget", dest="max_evals", type=int, default=600, help="most simulations of the fit"
    )
    p.add_argument("--workers", type=int, help="processes that simulate (default: the number of cores)")
    p.set_defaults(func=cmd_calibrate)
