"""Hardening, round 5 (issue 57): the files a run reads, non-finite numbers, secrets in errors, long
numbers, randomize ranges that cannot build. Each case: one line, a non-zero exit or an exception,
nothing replaced, nothing written, no secret in the output."""

from __future__ import annotations

import json
import os
import re
import shutil
import struct
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
import snakesim
from snakesim import files
from snakesim.cli import app as cli

REPO = Path(__file__).resolve().parents[2]
ROBOT = REPO / "robots" / "yaw-pitch-16.yaml"
# A password-file line: what a hostile model or a mistaken flag hands a parser.
SECRET = "VeryLongHashValueThatIsSecret"
SHADOW = f"root:$6$abcdefghSALT${SECRET}1234567890:19000:0:99999:7:::\ndaemon:*:19000:0:99999:7:::\n"


def _one_line_error(capsys, argv, code=1):
    try:
        got = cli.main([str(a) for a in argv])
    except SystemExit as stop:  # argparse's usage errors
        got = stop.code
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert got == code, err
    assert len([line for line in lines if not line.startswith("note:")]) == 1, err
    assert "error:" in lines[-1] and "Traceback" not in err, err
    assert SECRET not in out + err and "$6$" not in out + err, err
    assert not re.search(r"\d{21}", err), err  # numbers written short
    return lines[-1]


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}


@pytest.fixture
def robot_copy(tmp_path):
    """A copy of the yaw-pitch robot (its file and the URDF it names) in a folder of its own."""
    folder = tmp_path / "bots"
    folder.mkdir()
    for path in REPO.glob("robots/yaw-pitch-16.*"):
        shutil.copy(path, folder)
    return folder / "yaw-pitch-16.yaml"


# -- 1. outputs never replace a file the run reads, the files a robot or world names included ------


def test_evaluate_json_onto_the_urdf_a_robot_file_names_is_refused(robot_copy, capsys):
    before = _snapshot(robot_copy.parent)
    line = _one_line_error(
        capsys,
        [
            "evaluate",
            "baseline:steer",
            "--robot",
            robot_copy,
            "--episodes",
            "1",
            "--json",
            robot_copy.with_suffix(".urdf"),
        ],
    )
    assert "which this command reads" in line
    assert _snapshot(robot_copy.parent) == before


def test_outputs_onto_a_copied_models_robot_files_are_refused_however_spelled(tmp_path, capsys, monkeypatch):
    # A model and its robot copied elsewhere, evaluated from another directory.
    (tmp_path / "robots").mkdir()
    (tmp_path / "models").mkdir()
    for path in REPO.glob("robots/yaw-pitch-16.*"):
        shutil.copy(path, tmp_path / "robots")
    model = tmp_path / "models" / "goal-yaw-pitch-16.safetensors"
    shutil.copy(REPO / "models" / model.name, model)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    os.symlink(tmp_path / "robots" / "yaw-pitch-16.urdf", elsewhere / "link.json")
    os.link(tmp_path / "robots" / "yaw-pitch-16.yaml", elsewhere / "hard.json")
    before = _snapshot(tmp_path / "robots")
    for target in [
        tmp_path / "robots" / "yaw-pitch-16.urdf",
        tmp_path / "robots" / "yaw-pitch-16.yaml",
        "../robots/yaw-pitch-16.urdf",
        "link.json",
        "hard.json",
    ]:
        line = _one_line_error(capsys, ["evaluate", model, "--episodes", "1", "--json", target])
        assert "which this command reads" in line, line
    assert _snapshot(tmp_path / "robots") == before


def test_a_worlds_heightfield_is_an_input_the_library_never_replaces(tmp_path):
    heights = tmp_path / "hills.csv"
    heights.write_text("\n".join(",".join(["0.0"] * 8) for _ in range(8)) + "\n")
    world = tmp_path / "w.yaml"
    world.write_text("ground: {heightfield: {file: hills.csv, scale: [0.5, 0.5, 1.0]}}\n")
    before = heights.read_bytes()
    snakesim.SnakeEnv(world=str(world)).close()
    assert files.is_input(heights) and files.is_input(world)
    with pytest.raises(files.FileError, match="a file this run reads"):
        files.write_atomically(tmp_path / "." / "hills.csv", lambda tmp: Path(tmp).write_text("x"))
    assert heights.read_bytes() == before


def test_the_library_refuses_to_replace_what_it_read(robot_copy):
    env = snakesim.SnakeGoalEnv(robot=str(robot_copy))
    env.close()
    urdf = robot_copy.with_suffix(".urdf")
    before = urdf.read_bytes()
    with pytest.raises(files.FileError, match="a file this run reads"):
        files.write_atomically(urdf, lambda tmp: Path(tmp).write_text("<robot/>"))
    assert urdf.read_bytes() == before
    # A run's own state is rewritten on purpose, and says so.
    own = robot_copy.parent / "state.json"
    own.write_text("{}")
    files.read_text(own, "config_bytes")
    assert files.is_input(own)
    files.rewrite_atomically(own, lambda tmp: Path(tmp).write_text('{"a": 1}'))
    assert json.loads(own.read_text()) == {"a": 1}


# -- 2. YAML .nan / .inf never silently drop a setting ---------------------------------------------


@pytest.mark.parametrize("value", [".nan", ".inf", "-.inf", ".NaN"])
def test_set_with_a_non_finite_number_is_refused(value, tmp_path, capsys):
    line = _one_line_error(
        capsys,
        [
            "train",
            "--config",
            REPO / "snake-py/configs/paper-init-10.yaml",
            "--set",
            f"init.anchor={value}",
            "--run-dir",
            tmp_path / "run",
            "--timesteps",
            "64",
        ],
    )
    assert "init.anchor: must be a finite number" in line, line
    assert not (tmp_path / "run").exists()


def test_a_config_file_with_nan_is_refused_naming_the_key(tmp_path, capsys):
    config = tmp_path / "c.yaml"
    config.write_text("joints: 5\nenv:\n  randomize: {mass_scale: [.nan, 1.0]}\n")
    line = _one_line_error(
        capsys, ["train", "--config", config, "--run-dir", tmp_path / "run", "--timesteps", "64"]
    )
    assert "env.randomize.mass_scale[0]: must be a finite number, got .nan" in line, line
    assert not (tmp_path / "run").exists()


def test_a_randomize_file_with_nan_is_refused(tmp_path, capsys):
    rnd = tmp_path / "r.yaml"
    rnd.write_text("mass_scale: .nan\n")
    line = _one_line_error(
        capsys,
        ["evaluate", "baseline:steer", "--randomize", rnd, "--episodes", "1", "--json", tmp_path / "o.json"],
    )
    assert "mass_scale: must be a finite number, got .nan" in line, line
    assert not (tmp_path / "o.json").exists()


def test_snake_cli_refuses_non_finite_randomize(tmp_path):
    cli_bin = REPO / "target" / "release" / "snake-cli"
    if not cli_bin.exists():
        pytest.skip("snake-cli is not built")
    done = subprocess.run(
        [cli_bin, "env", "--episodes", "1", "--set", "randomize={mass_scale: .nan, obs_noise: .inf}"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode != 0 and "must be a finite number" in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "kwargs",
    [
        {"randomize": {"mass_scale": [float("nan"), 1.0]}},
        {"randomize": {"obs_noise": [0.0, float("inf")]}},
        {"goal_radius": float("nan")},
    ],
)
def test_python_keywords_with_non_finite_numbers_are_value_errors(kwargs):
    with pytest.raises(ValueError) as caught:
        snakesim.SnakeGoalEnv(**kwargs)
    assert "\n" not in str(caught.value)


def test_robot_and_world_files_refuse_non_finite_numbers(robot_copy, tmp_path):
    text = robot_copy.read_text()
    assert "kp:" in text
    robot_copy.write_text(re.sub(r"kp: [^\n,}]+", "kp: .nan", text, count=1))
    with pytest.raises(ValueError, match="must be a finite number, got .nan"):
        snakesim.SnakeGoalEnv(robot=str(robot_copy))
    world = tmp_path / "w.yaml"
    world.write_text("ground_friction: .inf\n")
    with pytest.raises(ValueError, match="ground_friction: must be a finite number, got .inf"):
        snakesim.SnakeEnv(world=str(world))


# -- 5. errors never quote secrets -----------------------------------------------------------------


def _hostile_native(tmp_path: Path, key: str, value: str) -> Path:
    """goal-10 with its env keywords naming ``key: value`` and no record of the file."""
    raw = (REPO / "models" / "goal-10.safetensors").read_bytes()
    (size,) = struct.unpack("<Q", raw[:8])
    header = json.loads(raw[8 : 8 + size])
    meta = header["__metadata__"]
    env = json.loads(meta["env"])
    env[key] = value
    meta["env"] = json.dumps(env)
    meta.pop("env_config", None)
    text = json.dumps(header).encode()
    text += b" " * (-len(text) % 8)
    out = tmp_path / "evil.safetensors"
    out.write_bytes(struct.pack("<Q", len(text)) + text + raw[8 + size :])
    return out


@pytest.fixture
def shadow(tmp_path):
    path = tmp_path / "shadow"
    path.write_text(SHADOW)
    return path


@pytest.mark.parametrize("key", ["world", "robot"])
def test_a_model_naming_a_file_without_its_record_is_refused_unopened(key, shadow, tmp_path, capsys):
    model = _hostile_native(tmp_path, key, str(shadow))
    opened = []

    def audit(event, args):
        if event == "open" and args and str(args[0]) == str(shadow):
            opened.append(args)

    sys.addaudithook(audit)  # (Python's opens; the Rust loader is shown by the message below)
    for argv in (
        ["evaluate", model, "--episodes", "1"],
        ["export", model, "--sb3", tmp_path / "x.zip"],
        ["evaluate", "baseline:steer", "--env-from", model, "--episodes", "1"],
    ):
        line = _one_line_error(capsys, argv)
        assert f"its env names the {key} file" in line and "holds no record" in line, line
    assert not opened
    assert not (tmp_path / "x.zip").exists()


def test_an_sb3_zip_naming_a_file_without_its_record_is_refused(shadow, tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    good = tmp_path / "g.zip"
    assert cli.main(["export", str(REPO / "models" / "goal-10.safetensors"), "--sb3", str(good)]) == 0
    capsys.readouterr()
    evil = tmp_path / "evil.zip"
    with zipfile.ZipFile(good) as src, zipfile.ZipFile(evil, "w") as out:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "data":
                content = json.loads(data)
                content["snakesim_env_kwargs"]["world"] = str(shadow)
                data = json.dumps(content).encode()
            out.writestr(item, data)
    line = _one_line_error(capsys, ["evaluate", evil, "--episodes", "1"])
    assert "its env names the world file" in line, line


@pytest.mark.parametrize("flag", ["--world", "--robot", "--targets"])
def test_snake_cli_never_quotes_a_password_file(flag, shadow, tmp_path):
    cli_bin = REPO / "target" / "release" / "snake-cli"
    if not cli_bin.exists():
        pytest.skip("snake-cli is not built")
    argv = [cli_bin, "run", "--output", tmp_path / "o.csv", flag, shadow]
    argv += ["--robot", ROBOT] if flag == "--targets" else ["--seconds", "1"]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60)
    assert done.returncode != 0
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert SECRET not in done.stderr and "$6$" not in done.stderr and "root:" not in done.stderr, done.stderr
    assert not (tmp_path / "o.csv").exists()


def test_a_randomize_file_holding_a_password_line_is_not_quoted(shadow, tmp_path, capsys):
    rnd = tmp_path / "r.yaml"
    rnd.write_text("mass_scale: [1, 1]\n" + SHADOW)
    line = _one_line_error(capsys, ["evaluate", "baseline:steer", "--randomize", rnd, "--episodes", "1"])
    assert "not shown" in line, line


# -- 9, 10. ranges that cannot build; numbers written short -----------------------------------------


def test_a_scale_that_cannot_build_is_refused_at_construction(capsys, tmp_path):
    with pytest.raises(ValueError, match=r"randomize.mass_scale: must lie within 0.01 <= low <= high <= 100"):
        snakesim.SnakeEnv(randomize={"mass_scale": [1e-300, 1e-300]})
    rnd = tmp_path / "r.yaml"
    rnd.write_text("kp_scale: [1, 1e300]\n")
    line = _one_line_error(capsys, ["evaluate", "baseline:steer", "--randomize", rnd, "--episodes", "1"])
    assert "got [1, 1e300]" in line, line


@pytest.mark.parametrize(
    "value, shown",
    [("lin_1e300", "1e300"), ("1e300", "1e300"), ("-1e-300", "1e-300")],
)
def test_numbers_in_errors_are_short(value, shown, tmp_path, capsys):
    line = _one_line_error(
        capsys,
        [
            "train",
            "--config",
            REPO / "snake-py/configs/paper-init-10.yaml",
            "--set",
            f"init.anchor={value}",
            "--run-dir",
            tmp_path / "run",
            "--timesteps",
            "64",
        ],
    )
    assert "init.anchor" in line and len(line) < 300, line
