"""`snakesim calibrate`: a small fit from a log made by pybullet 3.2.7 (tests/reference/calibration_log.py),
the simulation it fits bit for bit against pybullet and snake-cli run, its outputs and its one-line errors
on bad input (the 8 s, four-parameter fit of docs/calibration.md is a measurement, not a test)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from snakesim import _core
from snakesim.cli import app as cli
from snakesim.limits import LIMITS
from snakesim.runs.calibrate import FIT_KEYS, read_log, read_targets

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
    """The robot file knows the true gains; the fit finds the velocity limit and the ground friction."""
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
            "200",
            "--seed",
            "1",
        ]
    )
    assert code == 0, capsys.readouterr().err
    result = json.loads(report.read_text())
    for key in ("motors.max_velocity", "ground_friction"):
        assert abs(result["fitted"][key] / TRUTH[key] - 1) < 0.05, result
    assert result["error_after"] < result["error_before"]
    assert result["simulations"] <= 201 and result["wall_seconds"] > 0
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
        ("nan", "yaw2: 'inf' is not a finite number"),
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
        if key.startswith("skin_friction"):
            continue  # yaw-pitch-16 has no skin to fit
        _core.simulate_robot(str(ROBOT), targets, None, None, json.dumps({key: 0.5}))
    with pytest.raises(ValueError, match="unknown field"):
        _core.simulate_robot(str(ROBOT), targets, None, None, '{"motors.stiffness": 1}')
    assert os.path.exists(ROBOT)
