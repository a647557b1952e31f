"""`snakesim calibrate`: a small fit from a log made by pybullet 3.2.7 (tests/reference/calibration_log.py),
the simulation it fits bit for bit against pybullet and snake-cli run, its outputs and its one-line errors
on bad input (the 8 s, four-parameter fit of docs/calibration.md is a measurement, not a test)."""

import contextlib
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from snakesim import _core
from snakesim.cli import app as cli
from snakesim.limits import LIMITS
from snakesim.runs import calibrate as calibration
from snakesim.runs.calibrate import FIT_KEYS, CalibrationError, read_log, read_targets

pytest.importorskip("pybullet")
pytest.importorskip("cmaes")

REPO = Path(__file__).resolve().parents[2]
ROBOT = REPO / "robots" / "yaw-pitch-16.yaml"
TRUTH = {"motors.kp": 0.3, "motors.kd": 0.6, "motors.max_velocity": 4.0, "ground_friction": 0.8}


@pytest.fixture(scope="module")
def logged(tmp_path_factory) -> Path:
    """A 1.5 s pybullet log of yaw-pitch-16 with TRUTH's physics: targets.csv and log.csv."""
    out = tmp_path_factory.mktemp("log")
    subprocess.run(
        [sys.executable, str(REPO / "tests/reference/calibration_log.py"), str(out), "--seconds", "1.5"],
        check=True,
        capture_output=True,
    )
    return out


def _problem(logged: Path) -> tuple[np.ndarray, np.ndarray]:
    names = _core.robot_joint_names(str(ROBOT))
    targets = read_targets(logged / "targets.csv", names)
    return targets, read_log(logged / "log.csv", len(names), targets.shape[0])


def test_simulation_is_pybullet_bit_for_bit(logged):
    targets, log = _problem(logged)
    base, q = _core.simulate_robot(str(ROBOT), targets, None, None, json.dumps(TRUTH))
    assert np.array_equal(base, log[:, :7]) and np.array_equal(q, log[:, 7:])


def test_simulation_is_snake_cli_run(logged, tmp_path):
    """A fitted robot file and a world file with the ground friction, run by snake-cli run, give the
    trajectory simulate_robot gives for the same overrides."""
    cli_bin = REPO / "target" / "release" / "snake-cli"
    if not cli_bin.exists():
        pytest.skip("snake-cli is not built")
    from snakesim.runs.calibrate import fitted_robot_yaml

    robot = tmp_path / "fitted.yaml"
    robot.write_text(fitted_robot_yaml(ROBOT, TRUTH, robot))
    world = tmp_path / "world.yaml"
    world.write_text("ground_friction: 0.8\n")
    out = tmp_path / "run.csv"
    subprocess.run(
        [
            str(cli_bin),
            "run",
            "--robot",
            str(robot),
            "--targets",
            str(logged / "targets.csv"),
            "--world",
            str(world),
            "--start",
            "0,0,0.0254,0",
            "--output",
            str(out),
        ],
        check=True,
        capture_output=True,
    )
    targets, log = _problem(logged)
    run = read_log(out, targets.shape[1], targets.shape[0])
    assert np.array_equal(run, log)


def test_fits_two_parameters_within_5_percent(logged, tmp_path, capsys):
    """The robot file knows the true gains; the fit finds the velocity limit and the ground friction
    (over the default 0.25 s windows, in which the ground friction is gentler than over the whole run:
    400 simulations where the whole-run error took 200)."""
    from snakesim.runs.calibrate import fitted_robot_yaml

    robot = tmp_path / "robot.yaml"
    robot.write_text(fitted_robot_yaml(ROBOT, {"motors.kp": 0.3, "motors.kd": 0.6}, robot))
    out, report, figure = tmp_path / "fitted.yaml", tmp_path / "fit.json", tmp_path / "fit.png"
    code = cli.main(
        [
            "calibrate",
            "--robot",
            str(robot),
            "--targets",
            str(logged / "targets.csv"),
            "--log",
            str(logged / "log.csv"),
            "--fit",
            "motors.max_velocity=1:10",
            "--fit",
            "ground_friction=0.2:1.5",
            "--out",
            str(out),
            "--json",
            str(report),
            "--plot",
            str(figure),
            "--workers",
            "1",
            "--max-evals",
            "400",
            "--seed",
            "1",
        ]
    )
    assert code == 0, capsys.readouterr().err
    result = json.loads(report.read_text())
    for key in ("motors.max_velocity", "ground_friction"):
        assert abs(result["fitted"][key] / TRUTH[key] - 1) < 0.05, result
    assert result["error_after"] < result["error_before"]
    assert result["simulations"] <= 401 and result["wall_seconds"] > 0
    for key in ("motors.max_velocity", "ground_friction"):
        interval = result["intervals"][key]
        assert interval["identifiable"] and interval["low"] <= TRUTH[key] <= interval["high"], result
    assert set(result["bounds"]) == {"motors.max_velocity", "ground_friction"}
    # The fitted robot file is a robot file whose urdf: resolves, with the fitted gains.
    assert _core.robot_joint_names(str(out)) == _core.robot_joint_names(str(ROBOT))
    text = out.read_text()
    assert "max_velocity" in text and "yaw-pitch-16.urdf" in text
    assert figure.stat().st_size > 1000


def _run(args, tmp_path, capsys):
    out = tmp_path / "out.yaml"
    code = cli.main(
        ["calibrate", "--out", str(out), "--json", str(tmp_path / "r.json"), "--workers", "1", *args]
    )
    err = capsys.readouterr().err.strip()
    assert code != 0
    assert "\n" not in err, err
    assert not out.exists() and not (tmp_path / "r.json").exists()
    return err


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ("joints", "joint columns"),
        ("rows", "rows, the targets have"),
        ("nan", "not a finite number"),
        ("text", "is not a number"),
        ("cells", "cells, the header has"),
        ("unsorted", "expected 1 (rows sorted"),
        # t is read and checked: a number, step/240 s to the millisecond.
        ("banana", ':6: t: "banana" is not a number'),
        ("late", ':6: t: "0.025", expected step 5 x 1/240 s'),
        # Values beyond LIMITS['position'] (a 1e300 made every candidate's error overflow).
        ("absurd", ':6: base_x: "1e300" is beyond +-10000'),
        ("absurd_joint", ':6: q3: "-2e4" is beyond +-10000'),
    ],
)
def test_bad_logs_are_one_line(logged, tmp_path, capsys, change, expected):
    lines = (logged / "log.csv").read_text().splitlines()
    if change == "joints":
        lines = [",".join(line.split(",")[:-1]) for line in lines]
    elif change == "rows":
        lines = lines[:-1]
    elif change in ("nan", "text"):
        cells = lines[5].split(",")
        cells[3] = "nan" if change == "nan" else "1.0.0"
        lines[5] = ",".join(cells)
    elif change == "cells":
        lines[5] = lines[5].rsplit(",", 1)[0]
    elif change in ("banana", "late", "absurd", "absurd_joint"):
        cells = lines[5].split(",")
        column = {"banana": 1, "late": 1, "absurd": 2, "absurd_joint": 12}[change]
        cells[column] = {"banana": "banana", "late": "0.025", "absurd": "1e300", "absurd_joint": "-2e4"}[
            change
        ]
        lines[5] = ",".join(cells)
    else:
        lines[1], lines[2] = lines[2], lines[1]
    log = tmp_path / "bad.csv"
    log.write_text("\n".join(lines) + "\n")
    args = [
        "--robot",
        str(ROBOT),
        "--targets",
        str(logged / "targets.csv"),
        "--log",
        str(log),
        "--fit",
        "motors.kp=0.1:1",
    ]
    err = _run(args, tmp_path, capsys)
    assert expected in err and "bad.csv" in err, err


def test_log_over_the_size_limit(logged, tmp_path, capsys):
    log = tmp_path / "huge.csv"
    with open(log, "wb") as f:
        f.truncate(LIMITS["csv_bytes"] + 1)  # sparse: no disk used
    args = [
        "--robot",
        str(ROBOT),
        "--targets",
        str(logged / "targets.csv"),
        "--log",
        str(log),
        "--fit",
        "motors.kp=0.1:1",
    ]
    err = _run(args, tmp_path, capsys)
    assert "huge.csv" in err and "csv_bytes" in err, err


def _fit(targets, log, *fits):
    """The calibrate arguments of a fit of `fits` (KEY=LOW:HIGH each) on `targets` and `log`."""
    return ["--robot", str(ROBOT), "--targets", str(targets), "--log", str(log)] + [
        arg for fit in fits for arg in ("--fit", fit)
    ]


def test_targets_that_do_not_match_the_robot(logged, tmp_path, capsys):
    targets = tmp_path / "t.csv"
    lines = (logged / "targets.csv").read_text().splitlines()
    targets.write_text("\n".join(line.rsplit(",", 1)[0] for line in lines) + "\n")
    err = _run(_fit(targets, logged / "log.csv", "motors.kp=0.1:1"), tmp_path, capsys)
    assert "t.csv" in err, err


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ("nan", 'yaw2: "inf" is not a finite number'),
        ("unsorted", "expected 1 (rows sorted"),
        ("step", "the first column must be 'step'"),
        ("huge", "csv_bytes"),
    ],
)
def test_bad_targets_are_one_line(logged, tmp_path, capsys, change, expected):
    """Non-finite, unsorted, a table without its step column, over the size limit (missing a joint:
    test_targets_that_do_not_match_the_robot)."""
    targets = tmp_path / "bad.csv"
    lines = (logged / "targets.csv").read_text().splitlines()
    if change == "nan":
        cells = lines[5].split(",")
        cells[3] = "inf"
        lines[5] = ",".join(cells)
    elif change == "unsorted":
        lines[1], lines[2] = lines[2], lines[1]
    elif change == "step":
        lines[0] = "t" + lines[0].removeprefix("step")
    if change == "huge":
        with open(targets, "wb") as f:
            f.truncate(LIMITS["csv_bytes"] + 1)  # sparse: no disk used
    else:
        targets.write_text("\n".join(lines) + "\n")
    err = _run(_fit(targets, logged / "log.csv", "motors.kp=0.1:1"), tmp_path, capsys)
    assert expected in err and "bad.csv" in err, err


@pytest.mark.parametrize(
    ("fit", "expected"),
    [
        ("motors.stiffness=0.1:1", "unknown key"),
        ("motors.kp=1:0.1", "not below"),
        ("motors.kp=nan:1", "finite"),
        ("motors.kp=-1:1", "must be >= 0"),
        ("motors.kp", "expected KEY=LOW:HIGH"),
        ("motors.kp=a:1", "is not LOW:HIGH numbers"),
        # Bounds the simulation refuses: found before the fit, not by a candidate in the middle of it.
        ("motors.max_velocity=0:5", "motors.max_velocity: must be in (0, "),
        ("mass_scale=0.5:1e9", "mass_scale: must be in (0, 100]"),
        ("ground_friction=0.1:1e9", "ground_friction: must be in [0, 1000]"),
        ("skin_friction.forward=0.1:1", "the robot file sets no skin_friction to fit"),
    ],
)
def test_bad_fit_keys_are_one_line(logged, tmp_path, capsys, fit, expected):
    err = _run(_fit(logged / "targets.csv", logged / "log.csv", fit), tmp_path, capsys)
    assert expected in err and fit.split("=")[0] in err, err


def test_a_fit_key_given_twice_is_one_line(logged, tmp_path, capsys):
    fits = ("motors.kp=0.1:1", "motors.kp=0.2:2")
    err = _run(_fit(logged / "targets.csv", logged / "log.csv", *fits), tmp_path, capsys)
    assert "--fit motors.kp: given twice" in err, err


def test_every_fit_key_is_an_override():
    """Every key the command takes is one simulate_robot accepts (and nothing else is)."""
    targets = np.zeros((2, len(_core.robot_joint_names(str(ROBOT)))))
    for key in FIT_KEYS:
        if key.startswith(("skin_friction", "water.")):
            continue  # yaw-pitch-16 has no skin to fit, the plane no water
        _core.simulate_robot(str(ROBOT), targets, None, None, json.dumps({key: 0.5}))
    with pytest.raises(ValueError, match="unknown field"):
        _core.simulate_robot(str(ROBOT), targets, None, None, '{"motors.stiffness": 1}')
    assert os.path.exists(ROBOT)


def test_log_times_written_to_the_millisecond_are_read(logged, tmp_path):
    """t within 1 ms of step/240 s (a log's time stamps rounded) is a log; the values are the same."""
    lines = (logged / "log.csv").read_text().splitlines()
    rounded = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        cells[1] = f"{float(cells[1]):.3f}"
        rounded.append(",".join(cells))
    path = tmp_path / "rounded.csv"
    path.write_text("\n".join(rounded) + "\n")
    targets, log = _problem(logged)
    assert np.array_equal(read_log(path, targets.shape[1], targets.shape[0]), log)


# -- issue 57: --max-evals, candidates that all fail, strict JSON ---------------------------------------
def _no_nan(text: str) -> dict:
    """JSON as the standard reads it: NaN and Infinity are not JSON."""

    def refuse(constant):
        raise AssertionError(f"{constant} is not JSON")

    return json.loads(text, parse_constant=refuse)


def test_max_evals_below_one_generation_is_refused(logged, tmp_path, capsys):
    """It used to write the range's midpoint, never simulated, and "error_after": Infinity."""
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    err = _run([*args, "--max-evals", "7"], tmp_path, capsys)
    assert "--max-evals 7 is less than one generation" in err and "--max-evals 8 or more" in err, err
    # The population grows with the keys: 12 keys take 11 a generation.
    bounds = {key: (0.5, 1.0) for key in FIT_KEYS[:12]}
    with pytest.raises(CalibrationError, match="simulates 11 candidates a generation"):
        calibration.check_max_evals(10, len(bounds))
    calibration.check_max_evals(11, len(bounds))


def test_max_evals_of_one_generation_fits(logged, tmp_path, capsys):
    out, report = tmp_path / "fitted.yaml", tmp_path / "fit.json"
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    code = cli.main(
        ["calibrate", *args, "--out", str(out), "--json", str(report), "--workers", "1", "--max-evals", "8"]
    )
    assert code == 0, capsys.readouterr().err
    result = _no_nan(report.read_text())
    assert result["simulations"] == 9 and result["generations"] == 1 and result["failed_simulations"] == 0
    assert math.isfinite(result["error_after"]) and result["error_after"] <= result["error_before"]
    assert 0.1 <= result["fitted"]["motors.kp"] <= 1 and out.exists()


class _FailsAbove(calibration.Problem):
    """A problem whose simulation fails (as an unstable one does) for kp above `limit`."""

    limit = 0.3

    def error(self, values):
        if values.get("motors.kp", 0.0) > self.limit:
            return math.inf
        return super().error(values)


def test_a_failed_candidate_is_never_the_fit(logged):
    targets, log = _problem(logged)
    problem = _FailsAbove(str(ROBOT), targets, log)
    result = calibration.calibrate(problem, {"motors.kp": (0.05, 1.0)}, max_evals=16, seed=3)
    assert result["failed_simulations"] > 0
    assert result["fitted"]["motors.kp"] <= _FailsAbove.limit and math.isfinite(result["error_after"])
    _no_nan(json.dumps(result, allow_nan=False))


def test_no_candidate_with_a_finite_error_is_refused(logged):
    """Every error overflows (a log of 1e300, as read_log now refuses): no fit, rather than the
    sentinel error 1e12 reported as one."""
    targets, log = _problem(logged)
    problem = calibration.Problem(str(ROBOT), targets, np.full_like(log, 1e300))
    with pytest.raises(CalibrationError, match="no fit: every one of the 8 candidates' simulations failed"):
        calibration.calibrate(problem, {"motors.kp": (0.1, 1.0)}, max_evals=8)
    assert calibration.trajectory_error(log[:, :7], log[:, 7:], problem.log) == math.inf


def test_numbers_in_messages_are_short(logged, tmp_path, capsys):
    """A 1e300 bound and a forty-digit count are written short, not as hundreds of digits."""
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0:1e300")
    err = _run(args, tmp_path, capsys)
    assert "motors.kp" in err and "1e300" in err.replace("+", "") and not re.search(r"\d{30}", err), err
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    err = _run([*args, "--max-evals", "1" * 40], tmp_path, capsys)
    assert "--max-evals" in err and not re.search(r"\d{30}", err), err


# -- issue 57: outputs checked before the first simulation, written together or not at all -----------
@pytest.fixture
def no_simulation(monkeypatch):
    """Fails the test if anything is simulated (for outputs that must be refused before)."""

    def simulate(self, values):
        raise AssertionError("simulated before the outputs were checked")

    monkeypatch.setattr(calibration.Problem, "simulate", simulate)


@pytest.mark.parametrize("plot", ["fit", "fit.tmp", "fit.gif"])
def test_a_plot_without_a_figure_extension_is_refused_up_front(logged, tmp_path, capsys, no_simulation, plot):
    """It used to take the temporary file's random suffix for the format, after the fit."""
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    err = _run([*args, "--plot", str(tmp_path / plot)], tmp_path, capsys)
    assert f"--plot {tmp_path / plot}: expected a .png, .pdf or .svg file" in err, err
    assert not (tmp_path / plot).exists()


def test_a_fifo_that_nobody_reads_is_refused_up_front(logged, tmp_path, capsys, no_simulation):
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    code = cli.main(["calibrate", *args, "--out", str(tmp_path / "out.yaml"), "--json", str(fifo)])
    err = capsys.readouterr().err.strip()
    assert code == 1 and "\n" not in err and f"--json {fifo}: a FIFO that nobody reads" in err, err
    assert not (tmp_path / "out.yaml").exists()


def test_a_fifo_with_a_reader_gets_the_json(logged, tmp_path, capsys):
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    received: list[bytes] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()), daemon=True)
    reader.start()
    time.sleep(0.2)  # the reader opens the FIFO (an open for writing would otherwise be refused)
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    out = tmp_path / "out.yaml"
    code = cli.main(["calibrate", *args, "--out", str(out), "--json", str(fifo), "--max-evals", "8"])
    assert code == 0, capsys.readouterr().err
    reader.join(10)
    assert _no_nan(received[0].decode())["simulations"] == 9 and out.exists()
    assert fifo.exists() and not fifo.is_file()


def test_an_output_that_fails_replaces_no_other(logged, tmp_path, capsys):
    """--json /dev/full fails only when written, after the fit: --out keeps its old content."""
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    out = tmp_path / "out.yaml"
    out.write_text("old\n")
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    # --no-progress: the fit's progress lines (stderr, piped) would precede the one-line error.
    args += ["--no-progress"]
    code = cli.main(["calibrate", *args, "--out", str(out), "--json", "/dev/full", "--max-evals", "8"])
    err = capsys.readouterr().err.strip()
    assert code == 1 and "\n" not in err and "--json /dev/full" in err, err
    assert out.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["out.yaml"]


def test_a_failed_rename_puts_back_the_files_already_replaced(logged, tmp_path, capsys, monkeypatch):
    out, report = tmp_path / "out.yaml", tmp_path / "r.json"
    out.write_text("old\n")
    replace = os.replace

    def fail_for_the_json(src, dst):
        if os.fspath(dst) == os.path.realpath(report):
            raise OSError(28, "No space left on device")
        replace(src, dst)

    monkeypatch.setattr(os, "replace", fail_for_the_json)
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    code = cli.main(["calibrate", *args, "--out", str(out), "--json", str(report), "--max-evals", "8"])
    err = capsys.readouterr().err.strip()
    assert code == 1 and f"cannot write --json {report}: No space left on device" in err, err
    assert out.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["out.yaml"]


def test_a_plot_that_fails_writes_nothing(logged, tmp_path, capsys, monkeypatch):
    def fail(*args):
        raise OSError(5, "Input/output error", "fig.png")

    monkeypatch.setattr(calibration, "plot", fail)
    out, report, figure = tmp_path / "out.yaml", tmp_path / "r.json", tmp_path / "fig.png"
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    code = cli.main(
        [
            "calibrate",
            *args,
            "--out",
            str(out),
            "--json",
            str(report),
            "--plot",
            str(figure),
            "--max-evals",
            "8",
        ]
    )
    err = capsys.readouterr().err.strip()
    assert code == 1 and "Input/output error" in err, err
    assert list(tmp_path.iterdir()) == []


def test_outputs_may_not_replace_the_files_the_robot_and_world_name(tmp_path, logged, capsys, no_simulation):
    """--out D/yaw-pitch-16.urdf used to exit 0 and replace the URDF that D/yaw-pitch-16.yaml names
    with YAML; a world's heightfield CSV is an input as well."""
    for name in ("yaw-pitch-16.yaml", "yaw-pitch-16.urdf"):
        shutil.copy(ROBOT.parent / name, tmp_path / name)
    for name in ("hills.yaml", "hills.csv"):
        shutil.copy(REPO / "worlds" / name, tmp_path / name)
    urdf = (tmp_path / "yaw-pitch-16.urdf").read_bytes()
    base = ["calibrate", "--targets", str(logged / "targets.csv"), "--log", str(logged / "log.csv")]
    base += ["--robot", str(tmp_path / "yaw-pitch-16.yaml"), "--fit", "motors.kp=0.1:1"]
    for extra in (
        ["--out", str(tmp_path / "yaw-pitch-16.urdf")],
        ["--out", str(tmp_path / "fitted.yaml"), "--json", str(tmp_path / "hills.csv")],
    ):
        world = ["--world", str(tmp_path / "hills.yaml")]
        code = cli.main([*base, *world, *extra])
        err = capsys.readouterr().err.strip()
        assert code == 1 and "which this command reads" in err and "\n" not in err, err
    assert (tmp_path / "yaw-pitch-16.urdf").read_bytes() == urdf
    assert not (tmp_path / "fitted.yaml").exists()


def test_the_files_a_robot_and_a_world_read():
    assert sorted(_core.robot_files(str(ROBOT))) == sorted(
        [str(ROBOT), str(ROBOT.with_name("yaw-pitch-16.urdf"))]
    )
    assert _core.robot_files(str(ROBOT.with_suffix(".urdf"))) == [str(ROBOT.with_suffix(".urdf"))]
    hills = REPO / "worlds" / "hills.yaml"
    assert sorted(_core.world_files(str(hills))) == [str(hills.with_suffix(".csv")), str(hills)]


# -- issue 57: bounded inputs, interruptible simulations ------------------------------------------------
SMALL = REPO / "robots" / "paper-cubes-5.yaml"  # 5 joints


def _write_run(folder: Path, rows: int) -> tuple[Path, Path]:
    """A targets file and a (made-up, well-formed) log of `rows` rows for SMALL."""
    names = _core.robot_joint_names(str(SMALL))
    targets, log = folder / "targets.csv", folder / "log.csv"
    with open(targets, "w") as f:
        f.write(",".join(["step", *names]) + "\n")
        f.writelines(f"{k},0.3,-0.3,0.3,-0.3,0.3\n" for k in range(1, rows + 1))
    with open(log, "w") as f:
        f.write(",".join(_core.log_columns(len(names), False)) + "\n")
        f.writelines(f"{k},{k / 240!r},0,0,0.25,0,0,0,1,0,0,0,0,0\n" for k in range(1, rows + 1))
    return targets, log


def test_targets_over_the_row_limit_are_refused_while_read(tmp_path):
    """An hour of 1/240 s steps, as snake-cli run --targets: row 864,001 is refused as it is read,
    without holding the file's rows in memory (it took 1.18 GB for 53 MB of CSV, then simulated)."""
    rows = LIMITS["target_rows"]
    targets, _ = _write_run(tmp_path, 1)
    with open(targets, "a") as f:
        f.writelines(f"{k},0.3,-0.3,0.3,-0.3,0.3\n" for k in range(2, rows + 2))
    # VmHWM, the child's own peak: Linux carries ru_maxrss across exec, so the child of a test process
    # that has grown large (xdist runs many files in one) would report its parent's peak.
    probe = (
        "import sys; from snakesim.cli.app import main; code = main(sys.argv[1:]); "
        "print(next(l for l in open('/proc/self/status') if l.startswith('VmHWM')).split()[1]); "
        "sys.exit(code)"
    )
    args = ["calibrate", "--robot", str(SMALL), "--targets", str(targets), "--log", str(targets)]
    args += ["--fit", "motors.kp=0.1:1", "--out", str(tmp_path / "out.yaml")]
    start = time.monotonic()
    run = subprocess.run([sys.executable, "-c", probe, *args], capture_output=True, text=True, timeout=120)
    seconds = time.monotonic() - start
    assert run.returncode == 1, run.stderr
    assert f"targets.csv:{rows + 2}: more than 864,000 rows (LIMITS['target_rows']" in run.stderr
    peak_mb = int(run.stdout.split()[-1]) / 1024
    # ~80 MB on the development machine (the interpreter and numpy ~47 MB, the rows 35 MB).
    assert peak_mb < 250, peak_mb
    assert seconds < 60, seconds
    assert not (tmp_path / "out.yaml").exists()


def _children(pid: int) -> list[int]:
    try:
        return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux's /proc")
@pytest.mark.parametrize(
    ("workers", "sig", "code"), [(1, "SIGINT", 130), (1, "SIGTERM", 143), (2, "SIGINT", 130)]
)
def test_a_long_simulation_is_interrupted_at_once(tmp_path_factory, workers, sig, code):
    """Ctrl-C (and SIGTERM) used to wait for the simulation: 10 minutes on a million rows. Now the
    process answers within 2 s, in the main process (--workers 1) or with the simulations in spawned
    worker processes (which end too), writes nothing and exits 130 (143). With workers the signal goes
    to the whole process group, as a terminal's Ctrl-C does: the workers print nothing."""
    folder = tmp_path_factory.mktemp("interrupt")
    targets, log = _write_run(folder, 30_000)  # ~2.5 s a simulation
    out = folder / "out.yaml"
    args = ["calibrate", "--robot", str(SMALL), "--targets", str(targets), "--log", str(log)]
    args += ["--fit", "motors.kp=0.1:1", "--out", str(out), "--workers", str(workers)]
    process = subprocess.Popen(
        [sys.executable, "-m", "snakesim", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    workers_seen: list[int] = []
    try:
        deadline = time.monotonic() + 120
        if workers == 1:
            time.sleep(2.0)  # reading the files or simulating
        else:
            # The first simulation runs in the main process; then the workers start (and the
            # resource tracker), import snakesim and simulate.
            while len(_children(process.pid)) <= workers and time.monotonic() < deadline:
                time.sleep(0.1)
            time.sleep(2.0)
            workers_seen = _children(process.pid)
            assert len(workers_seen) > workers, "no workers"
        assert process.poll() is None, process.communicate()
        sent = time.monotonic()
        if workers == 1:
            process.send_signal(getattr(signal, sig))
        else:
            os.killpg(process.pid, getattr(signal, sig))
        stdout, stderr = process.communicate(timeout=30)
        answered = time.monotonic() - sent
    except BaseException:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)
        raise
    assert answered < 2.0, answered
    assert process.returncode == code, stderr
    assert stderr.strip() == f"snakesim calibrate: {'interrupted' if code == 130 else 'terminated'}"
    assert sorted(p.name for p in folder.iterdir()) == ["log.csv", "targets.csv"]
    deadline = time.monotonic() + 5  # the resource tracker ends once its pipe closes
    while any(map(_alive, workers_seen)) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert [pid for pid in workers_seen if _alive(pid)] == []


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"  # a zombie has ended (its reaper may be slow)


def test_piped_progress_is_a_line_per_generation_on_stderr(logged, tmp_path):
    """Piped: one line per generation of CMA-ES on stderr (none on stdout), `--json -` JSON alone."""
    args = ["--robot", ROBOT, "--targets", logged / "targets.csv", "--log", logged / "log.csv"]
    args += ["--fit", "ground_friction=0.2:1.5", "--out", tmp_path / "f.yaml", "--workers", 1]
    args += ["--max-evals", 12, "--json", "-"]
    done = subprocess.run(
        [sys.executable, "-m", "snakesim", "calibrate", *map(str, args)], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    *lines, last = done.stderr.splitlines()
    assert lines and all(re.match(r"calibrate: \d+/12 simulations, .*best error", line) for line in lines)
    assert "\r" not in done.stdout + done.stderr
    assert lines[-1].startswith(f"calibrate: {result['simulations'] - 1}/12 simulations")
    # Then the intervals, which the search's count does not hold, on a line of their own.
    assert last == "calibrate: the intervals of 1 key(s), about 35 simulations", last


# -- issue 61: windows, restarts, intervals, designed targets ---------------------------------------------
# The robot and log, made by pybullet 3.2.7 (tests/reference/calibration_log.py --cylinders 9):
# nine cylinder modules, eight joints, smooth random targets, physics the fit is not told.
SMOOTH_TRUTH = {"motors.kp": 0.23, "motors.kd": 0.65, "motors.max_velocity": 2.3, "ground_friction": 0.82}
SMOOTH_BOUNDS = {
    "motors.kp": (0.05, 0.6),
    "motors.kd": (0.2, 2.0),
    "motors.max_velocity": (0.5, 5.0),
    "ground_friction": (0.2, 1.5),
}
CYLINDERS_START = "0,0,0.025,0"


def _pybullet_log(out: Path, seconds: float, targets: str, *extra: str) -> Path:
    truth = [f"--kp={SMOOTH_TRUTH['motors.kp']}", f"--kd={SMOOTH_TRUTH['motors.kd']}"]
    truth += [f"--max-velocity={SMOOTH_TRUTH['motors.max_velocity']}"]
    truth += [f"--ground-friction={SMOOTH_TRUTH['ground_friction']}"]
    subprocess.run(
        [sys.executable, str(REPO / "tests/reference/calibration_log.py"), str(out), "--cylinders", "9"]
        + ["--start", CYLINDERS_START, "--seconds", str(seconds), "--targets", targets, *truth, *extra],
        check=True,
        capture_output=True,
    )
    return out


@pytest.fixture(scope="module")
def smooth_logged(tmp_path_factory) -> Path:
    """A 2 s pybullet log of the issue's robot under smooth random targets (robot.urdf, targets.csv,
    log.csv), and beside it (velocities/) the same run logged with its velocities."""
    out = _pybullet_log(tmp_path_factory.mktemp("smooth"), 2.0, "smooth")
    _pybullet_log(out / "velocities", 2.0, "smooth", "--velocities")
    return out


def _smooth_problem(folder: Path, window: float) -> calibration.Problem:
    robot = str(folder / "robot.urdf")
    names = _core.robot_joint_names(robot)
    targets = read_targets(folder / "targets.csv", names)
    log = read_log(folder / "log.csv", len(names), targets.shape[0])
    start = tuple(float(v) for v in CYLINDERS_START.split(","))
    return calibration.Problem(robot, targets, log, start=start, window=round(window * 240))


def test_the_truth_restarted_from_the_log_is_the_log(smooth_logged):
    """Windows restarted from the logged state, its velocities estimated from the positions or read
    from the log: the truth reproduces pybullet's log to rounding, where a 1e-4 change of kp over
    the whole run misses by an error of about 1 (0.15 cm or 0.15 mrad RMS, on this 2 s log)."""
    estimated = _smooth_problem(smooth_logged, 0.25)
    logged = _smooth_problem(smooth_logged / "velocities", 0.25)
    assert logged.log.shape[1] == 7 + 8 + 6 + 8 and estimated.log.shape[1] == 7 + 8
    assert np.array_equal(logged.log[:, : 7 + 8], estimated.log)
    # Backward differences are Bullet's own velocities (semi-implicit Euler) to rounding.
    assert np.abs(logged.states - estimated.states).max() < 1e-9
    assert estimated.error(SMOOTH_TRUTH) < 1e-12 and logged.error(SMOOTH_TRUTH) < 1e-12
    assert estimated.error(SMOOTH_TRUTH, whole=True) == 0.0
    # A small change is a small error over windows (smooth), not a needle.
    near = {**SMOOTH_TRUTH, "motors.kp": 0.23 * 1.01}
    assert 0 < estimated.error(near) < 0.1


def test_windows_restarts_and_intervals_fit_the_smooth_random_log(smooth_logged):
    """The issue's case on a 2 s log (docs/calibration.md measures the 8 s one): each value within 5 %
    of the truth or reported not identifiable with its reason; every interval holds the truth."""
    problem = _smooth_problem(smooth_logged, 0.25)
    result = calibration.calibrate(problem, SMOOTH_BOUNDS, max_evals=560, seed=0)
    json.dumps(result, allow_nan=False)
    for key, truth in SMOOTH_TRUTH.items():
        interval = result["intervals"][key]
        assert interval["low"] <= truth <= interval["high"], (key, interval, result["fitted"])
        if interval["identifiable"]:
            assert abs(result["fitted"][key] / truth - 1) < 0.05, (key, result["fitted"], interval)
        else:
            assert interval["reason"].startswith("not identifiable from this log"), interval
    assert result["intervals"]["motors.max_velocity"]["identifiable"], result["intervals"]
    assert result["error_after"] < 0.01 and result["whole_run_error_after"] is not None
    assert result["restarts"][0]["stopped"] in ("settled", "converged"), result["restarts"]


def test_the_fitted_file_replays_the_fitted_run_per_link_values_included(logged, tmp_path):
    """The head's own anisotropic friction used to be left out of the fitted file (written in Python
    while the simulation applied the values in Rust): it replayed 0.48 m off over 2 s. One mapping now
    (snake-core's fitted_robot_file): bit for bit, with the per-link and per-joint values."""
    from snakesim.runs.calibrate import fitted_robot_yaml

    robot = tmp_path / "robot.yaml"
    robot.write_text(
        f"urdf: {ROBOT.with_suffix('.urdf')}\nstart: [0, 0, 0.0254, 0]\nmotors: {{kp: 0.1, kd: 1.0}}\n"
        "anisotropic_friction: [1, 0.8, 0.8]\nlinks:\n  module0: {anisotropic_friction: [1, 0.5, 0.5]}\n"
        "joints:\n  yaw0: {max_velocity: 2.0}\n"
    )
    fitted = {
        "motors.kp": 0.3,
        "motors.kd": 0.6,
        "motors.max_velocity": 4.0,
        "anisotropic_friction.y": 0.05,  # z is the head's own (0.5) and the others' (0.8)
    }
    out = tmp_path / "sub" / "fitted.yaml"
    out.parent.mkdir()
    out.write_text(fitted_robot_yaml(robot, fitted, out))
    names = _core.robot_joint_names(str(ROBOT))
    targets = read_targets(logged / "targets.csv", names)
    base, q = _core.simulate_robot(str(robot), targets, None, None, json.dumps(fitted))
    replay_base, replay_q = _core.simulate_robot(str(out), targets)
    assert np.array_equal(base, replay_base) and np.array_equal(q, replay_q)
    # The head's own value matters: a file without it (what the Python writer gave) runs another way.
    plain = tmp_path / "plain.yaml"
    plain.write_text(robot.read_text().replace("  module0: {anisotropic_friction: [1, 0.5, 0.5]}\n", ""))
    without_head, _ = _core.simulate_robot(str(plain), targets, None, None, json.dumps(fitted))
    assert np.abs(without_head[:, :3] - base[:, :3]).max() > 1e-3


@pytest.mark.parametrize(
    ("window", "expected"),
    [
        ("0.001", "--window 0.001: shorter than one physics step (1/240 s"),
        ("1.6", "--window 1.6: longer than --log"),
        ("-1", "expected finite seconds >= 0"),
        ("nan", "expected finite seconds >= 0"),
    ],
)
def test_a_window_the_log_cannot_hold_is_one_line(logged, tmp_path, capsys, no_simulation, window, expected):
    args = _fit(logged / "targets.csv", logged / "log.csv", "motors.kp=0.1:1")
    if window in ("-1", "nan"):
        with pytest.raises(SystemExit):
            cli.main(["calibrate", *args, "--out", str(tmp_path / "o.yaml"), "--window", window])
        err = capsys.readouterr().err.strip().splitlines()[-1]
    else:
        err = _run([*args, "--window", window], tmp_path, capsys)
    assert expected in err, err


def test_a_log_with_some_velocity_columns_names_the_missing_ones(smooth_logged, tmp_path, capsys):
    """Velocities are read from the log when it has them all, estimated when it has none; some of them
    is a one-line error naming the missing columns."""
    lines = (smooth_logged / "velocities" / "log.csv").read_text().splitlines()
    header = lines[0].split(",")
    keep = [i for i, name in enumerate(header) if name not in ("base_wz", "qd7")]
    log = tmp_path / "partial.csv"
    log.write_text("\n".join(",".join(line.split(",")[i] for i in keep) for line in lines) + "\n")
    args = ["--robot", str(smooth_logged / "robot.urdf"), "--targets", str(smooth_logged / "targets.csv")]
    args += ["--log", str(log), "--fit", "motors.kp=0.1:1"]
    err = _run(args, tmp_path, capsys)
    assert "partial.csv:1: the log has velocity columns but lacks base_wz, qd7" in err, err


def test_designed_targets_are_written_for_the_robot(tmp_path, capsys):
    out = tmp_path / "design.csv"
    code = cli.main(["calibrate", "--robot", str(ROBOT), "--design-targets", str(out), "--seconds", "2"])
    assert code == 0, capsys.readouterr().err
    names = _core.robot_joint_names(str(ROBOT))
    table = read_targets(out, names)
    assert table.shape == (480, len(names)) and np.abs(table).max() <= 0.6 + 1e-12
    # Steps: the first part switches between +-0.6 rad from one step to the next.
    assert np.abs(np.diff(table[:192], axis=0)).max() == pytest.approx(1.2)
    for bad, expected in ((["--seconds", "0"], "--seconds must be in"), ([], "--robot")):
        robot = ["--robot", str(tmp_path / "none.yaml")] if not bad else ["--robot", str(ROBOT)]
        code = cli.main(["calibrate", *robot, "--design-targets", str(tmp_path / "d2.csv"), *bad])
        err = capsys.readouterr().err.strip()
        assert code == 1 and expected in err and "\n" not in err, err
    assert not (tmp_path / "d2.csv").exists()


def test_the_designed_targets_make_all_four_identifiable(smooth_logged, tmp_path, capsys):
    """--design-targets for the issue's robot, run by pybullet with the truth (2 s here; the 8 s log is
    measured in docs/calibration.md): all four values identifiable, within 5 %, inside their intervals."""
    targets = tmp_path / "targets.csv"
    code = cli.main(
        ["calibrate", "--robot", str(smooth_logged / "robot.urdf"), "--design-targets", str(targets)]
        + ["--seconds", "2"]
    )
    assert code == 0, capsys.readouterr().err
    folder = _pybullet_log(tmp_path / "design", 2.0, str(targets))
    problem = _smooth_problem(folder, 0.25)
    result = calibration.calibrate(problem, SMOOTH_BOUNDS, max_evals=560, seed=0)
    for key, truth in SMOOTH_TRUTH.items():
        interval = result["intervals"][key]
        assert interval["identifiable"] and interval["low"] <= truth <= interval["high"], (key, interval)
        assert abs(result["fitted"][key] / truth - 1) < 0.05, (key, result["fitted"])


def test_intervals_are_the_profile_of_a_known_error():
    """Against closed forms: for E = E0 + a (u0 - c)^2 the interval of u0 is c +- sqrt(DELTA / a); for an
    error in which u0 and u1 trade off (E = (u0 - u1)^2 + b (u0 + u1 - 1)^2) it is the profile's, wider
    than a slice through the fit; a key the error ignores is not identifiable, with the reason."""
    from snakesim.runs import calibrate_intervals as ci

    def batch(f):
        return lambda xs: [f(np.asarray(x)) for x in xs]

    keys, identity = ["motors.kp", "ground_friction"], (lambda i, u: u)
    a, e0 = 40.0, 0.05
    delta = ci.delta_for(e0)
    result, spent = ci.intervals(
        batch(lambda u: e0 + a * (u[0] - 0.4) ** 2), keys, identity, np.array([0.4, 0.5]), e0
    )
    half = math.sqrt(delta / a)
    kp = result["motors.kp"]
    assert kp["identifiable"] and kp["low"] == pytest.approx(0.4 - half, abs=0.004), kp
    assert kp["high"] == pytest.approx(0.4 + half, abs=0.004), kp
    friction = result["ground_friction"]
    assert not friction["identifiable"] and (friction["low"], friction["high"]) == (0.0, 1.0)
    assert friction["reason"].startswith("not identifiable from this log: the error stays within 0.1")
    assert "lower and upper bounds" in friction["reason"] and "slide" in friction["reason"]
    assert spent < 80
    # Trading off: E = (u0 - u1)^2 + b (u0 + u1 - 1)^2, minimum 0 at (0.5, 0.5). With u1 free, the
    # profile of u0 is E = 4b/(1 + b) (u0 - 0.5)^2; a slice (u1 held) would give (1 + b) (u0 - 0.5)^2.
    b = 0.01
    result, _ = ci.intervals(
        batch(lambda u: (u[0] - u[1]) ** 2 + b * (u[0] + u[1] - 1) ** 2),
        keys,
        identity,
        np.array([0.5, 0.5]),
        0.0,
    )
    profile = math.sqrt(ci.DELTA * (1 + b) / (4 * b))  # 1.59: past both bounds
    assert profile > 0.5 and not result["motors.kp"]["identifiable"], result
    b = 0.25  # profile half-width 0.354, a slice's 0.283
    result, _ = ci.intervals(
        batch(lambda u: (u[0] - u[1]) ** 2 + b * (u[0] + u[1] - 1) ** 2),
        keys,
        identity,
        np.array([0.5, 0.5]),
        0.0,
    )
    profile = math.sqrt(ci.DELTA * (1 + b) / (4 * b))
    assert result["motors.kp"]["high"] == pytest.approx(0.5 + profile, abs=0.01), result
    assert result["motors.kp"]["low"] == pytest.approx(0.5 - profile, abs=0.01), result
