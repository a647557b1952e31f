"""A model records the robot it was trained on (issue 47): editing the robot file afterwards never
changes the agent. Native and SB3 runs on a copy of robots/paper-cubes-5 (5 joints, fast), trained a
few hundred timesteps; the reference env is built from an untouched copy of the shipped files."""

import json
import os
import shutil
import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from snakesim.agents import loading
from snakesim.agents.loading import AgentError, load_agent
from snakesim.cli import app as cli
from snakesim.envs.env import make_env

REPO = Path(__file__).resolve().parents[2]
NAME = "paper-cubes-5"
# Relative to the training directory; not a directory of the repository's root (the tests' working
# directory), so a loader finds it beside the model's directory, as the shipped models find robots/.
ROBOT = f"bots/{NAME}.yaml"
ENV = {"task": "goal", "robot": ROBOT, "max_episode_steps": 100}
TINY = {
    "joints": 5,
    "n_envs": 2,
    "timesteps": 256,
    "eval_freq": 0,
    "checkpoint_freq": 0,
    "ppo": {"n_steps": 128, "batch_size": 128, "n_epochs": 1},
    "env": ENV,
}


def copy_robot(where: Path) -> Path:
    """The shipped robot file and its URDF copied to ``where/bots``; the robot file's path."""
    (where / "bots").mkdir(parents=True)
    for suffix in ("yaml", "urdf"):
        shutil.copy(REPO / "robots" / f"{NAME}.{suffix}", where / "bots" / f"{NAME}.{suffix}")
    return where / ROBOT


def train(base: Path, trainer: dict) -> Path:
    """A tiny run trained in ``base`` (its working directory) on a copy of the robot; its model."""
    copy_robot(base)
    config = base / "config.yaml"
    config.write_text(yaml.safe_dump({**TINY, **trainer}))
    here = os.getcwd()
    os.chdir(base)
    try:
        assert cli.main(["train", "--config", str(config), "--run-dir", "run", "--no-progress"]) == 0
    finally:
        os.chdir(here)
    return base / "run" / ("model.safetensors" if trainer["trainer"] == "native" else "model.zip")


@pytest.fixture(scope="module")
def native_model(tmp_path_factory):
    return train(tmp_path_factory.mktemp("recorded-native"), {"trainer": "native", "threads": 1})


SB3 = {
    "trainer": "sb3",
    "device": "cpu",
    "torch_threads": 1,
    "ppo": {"n_steps": 128, "batch_size": 128, "n_epochs": 1},
}


@pytest.fixture(scope="module")
def sb3_model(tmp_path_factory):
    return train(tmp_path_factory.mktemp("recorded-sb3"), SB3)


def placed(model: Path, where: Path) -> Path:
    """The model copied to ``where/models`` with the robot copied beside, as trained; its copy."""
    copy_robot(where)
    (where / "models").mkdir()
    return Path(shutil.copy(model, where / "models" / model.name))


def load_copy(kind: str, model: Path, where: Path, monkeypatch, change=None):
    """A copy of the run's model with a copy of the robot files (through ``change``), loaded: a
    native model from ``where/models`` (it finds ``bots/`` beside), an SB3 run's directory from
    ``where`` (its config names ``bots/`` relative to the directory it ran in). The agent, the
    robot's path as the loader sees it and what it wrote to stderr."""
    if kind == "native":
        copy = placed(model, where)
        shown = str(where / ROBOT)
    else:
        copy = Path(shutil.copytree(model.parent, where / "run"))
        copy_robot(where)
        monkeypatch.chdir(where)
        shown = ROBOT
    if change is not None:
        change(where)
    return load_agent(copy), shown


def trajectory(env_kwargs: dict, steps: int = 40) -> np.ndarray:
    """Observations of the env of ``env_kwargs`` under fixed actions from a fixed reset."""
    env = make_env(**env_kwargs)
    obs, _ = env.reset(seed=7)
    actions = np.random.default_rng(3).uniform(-1, 1, (steps, env.action_space.shape[0]))
    rows = [obs]
    for action in actions:
        obs, *_ = env.step(action)
        rows.append(obs)
    return np.array(rows)


def edit_robot(where: Path) -> None:
    """A stiffer motor in the robot file and a heavier head in its URDF."""
    robot = where / ROBOT
    robot.write_text(robot.read_text().replace("kp: 0.1,", "kp: 0.4,"))
    urdf = robot.with_suffix(".urdf")
    urdf.write_text(urdf.read_text().replace('<mass value="0.06"/>', '<mass value="0.2"/>', 1))


def reference(tmp_path: Path) -> dict:
    """The env keywords of the run on an untouched copy of the shipped robot files."""
    return {**ENV, "robot": str(copy_robot(tmp_path / "reference"))}


@pytest.mark.parametrize("kind", ["native", "sb3"])
def test_an_edited_robot_file_does_not_change_the_agent(kind, request, tmp_path, capsys, monkeypatch):
    expected = trajectory(reference(tmp_path))
    model = request.getfixturevalue(f"{kind}_model")
    capsys.readouterr()
    agent, shown = load_copy(kind, model, tmp_path / "copy", monkeypatch, edit_robot)
    err = capsys.readouterr().err
    notes = [line for line in err.splitlines() if line.startswith("note:")]
    assert len(notes) == 1, err
    assert f"robot {shown} changed since training ({NAME}.urdf differs, {NAME}.yaml differs)" in notes[0]
    assert notes[0].endswith("the robot recorded in the model is used"), notes
    assert isinstance(agent.env_kwargs["robot"], dict)
    assert "as recorded" in agent.body
    np.testing.assert_array_equal(trajectory(agent.env_kwargs), expected)
    # The edit matters: the edited file alone gives another robot.
    edited = {**ENV, "robot": str(tmp_path / "copy" / ROBOT)}
    assert not np.array_equal(trajectory(edited), expected)


def test_a_bare_sb3_zip_keeps_its_env_and_its_record(sb3_model, tmp_path, capsys, monkeypatch):
    """The SB3 trainer's zip copied out of its run (no config.yaml beside): its env keywords and
    robot record travel in the zip, so it loads on the robot it was trained on, not a guess."""
    expected = trajectory(reference(tmp_path))
    model = placed(sb3_model, tmp_path / "copy")
    edit_robot(tmp_path / "copy")
    monkeypatch.chdir(tmp_path / "copy")
    capsys.readouterr()
    agent = load_agent(model)
    assert "the robot recorded in the model is used" in capsys.readouterr().err
    assert {k: agent.env_kwargs[k] for k in ("task", "max_episode_steps", "joints")} == {
        "task": "goal",
        "max_episode_steps": 100,
        "joints": 5,
    }
    np.testing.assert_array_equal(trajectory(agent.env_kwargs), expected)


@pytest.mark.parametrize("kind", ["native", "sb3"])
def test_a_resumed_run_goes_on_with_the_robot_it_trained_on(kind, tmp_path, capsys, monkeypatch):
    """The robot file edited between a run and its --resume: the run goes on with the recorded robot
    (one note), and its final model records and acts on the robot as first trained."""
    trainer = {"trainer": "native", "threads": 1} if kind == "native" else SB3
    base = tmp_path / "run-base"
    copy_robot(base)
    (base / "config.yaml").write_text(yaml.safe_dump({**TINY, **trainer, "checkpoint_freq": 256}))
    monkeypatch.chdir(base)
    assert cli.main(["train", "--config", "config.yaml", "--run-dir", "run", "--no-progress"]) == 0
    edit_robot(base)
    capsys.readouterr()
    argv = ["train", "--run-dir", "run", "--resume", "--timesteps", "512", "--no-progress"]
    assert cli.main(argv) == 0, capsys.readouterr().err
    notes = [line for line in capsys.readouterr().err.splitlines() if "changed since training" in line]
    assert len(notes) == 1, notes
    assert f"robot {ROBOT} changed since training" in notes[0]
    model = base / "run" / ("model.safetensors" if kind == "native" else "model.zip")
    expected = {
        f"{NAME}.{suffix}": (REPO / "robots" / f"{NAME}.{suffix}").read_text() for suffix in ("yaml", "urdf")
    }
    if kind == "native":
        record = json.loads(header(model)["__metadata__"]["env_files"])
    else:
        with zipfile.ZipFile(model) as archive:
            record = json.loads(archive.read("data"))[loading.RECORDED_FILES_KEY]
    assert record["robot"]["files"] == expected
    agent = load_agent(model)
    np.testing.assert_array_equal(trajectory(agent.env_kwargs), trajectory(reference(tmp_path)))


def test_a_missing_robot_file_is_replaced_by_the_record(native_model, tmp_path, capsys):
    model = placed(native_model, tmp_path / "copy")
    (tmp_path / "copy" / ROBOT).with_suffix(".urdf").unlink()
    capsys.readouterr()
    agent = load_agent(model)
    assert f"({NAME}.urdf is missing)" in capsys.readouterr().err
    np.testing.assert_array_equal(trajectory(agent.env_kwargs), trajectory(reference(tmp_path)))


@pytest.mark.parametrize("kind", ["native", "sb3"])
def test_unchanged_files_load_as_before_without_a_note(kind, request, tmp_path, capsys, monkeypatch):
    model = request.getfixturevalue(f"{kind}_model")
    capsys.readouterr()
    agent, shown = load_copy(kind, model, tmp_path / "copy", monkeypatch)
    assert "note:" not in capsys.readouterr().err
    assert agent.env_kwargs["robot"] == shown


def test_the_record_holds_the_files_as_trained(native_model, sb3_model):
    expected = {
        f"{NAME}.{suffix}": (REPO / "robots" / f"{NAME}.{suffix}").read_text() for suffix in ("yaml", "urdf")
    }
    meta = header(native_model)["__metadata__"]
    assert json.loads(meta["env_files"]) == {"robot": {"path": ROBOT, "files": expected}}
    with zipfile.ZipFile(sb3_model) as archive:
        data = json.loads(archive.read("data"))
    assert data[loading.RECORDED_FILES_KEY] == {"robot": {"path": ROBOT, "files": expected}}


def header(model: Path) -> dict:
    raw = model.read_bytes()
    (size,) = struct.unpack("<Q", raw[:8])
    return json.loads(raw[8 : 8 + size])


def with_record(model: Path, target: Path, change) -> Path:
    """A copy of a native model at ``target`` whose ``env_files`` record went through ``change``."""
    raw = model.read_bytes()
    (size,) = struct.unpack("<Q", raw[:8])
    head = json.loads(raw[8 : 8 + size])
    meta = head["__metadata__"]
    record = json.loads(meta["env_files"])
    meta["env_files"] = change(record) if callable(change) else change
    if not isinstance(meta["env_files"], str):
        meta["env_files"] = json.dumps(meta["env_files"])
    encoded = json.dumps(head).encode()
    encoded += b" " * (-len(encoded) % 8)
    target.write_bytes(struct.pack("<Q", len(encoded)) + encoded + raw[8 + size :])
    return target


def garbled_urdf(record):
    record["robot"]["files"][f"{NAME}.urdf"] = "<robot name='x'><link"
    return record


def extra_file(record):
    record["robot"]["files"]["other.txt"] = "x"
    return record


def no_urdf(record):
    del record["robot"]["files"][f"{NAME}.urdf"]
    return record


def renamed(record):
    record["robot"]["path"] = "bots/another.yaml"
    return record


def unknown_key(record):
    record["robot"]["sha256"] = "0"
    return record


@pytest.mark.parametrize(
    "change, message",
    [
        ("{not json", "metadata 'env_files' is not JSON"),
        ([1, 2], "metadata 'env_files' is not a JSON mapping"),
        ({"robot": "bots/x.yaml"}, "metadata 'env_files': robot: invalid type"),
        (
            {"terrain": {"path": "x", "files": {}}},
            "metadata 'env_files' records 'terrain', not a robot or world",
        ),
        ({"world": {"path": "w.yaml", "files": {}}}, "records a world file, but its env has no world file"),
        (renamed, f"records the robot bots/another.yaml, but its env's robot is {ROBOT}"),
        (unknown_key, "unknown field `sha256`"),
        (garbled_urdf, "not XML"),
        (extra_file, "the record holds files it does not use: other.txt"),
        (no_urdf, f"URDF bots/{NAME}.urdf: not among the recorded files ({NAME}.yaml)"),
    ],
)
def test_a_bad_record_is_a_one_line_error(native_model, tmp_path, change, message, monkeypatch):
    # Loaded from the training directory, with the robot files there unchanged.
    monkeypatch.chdir(native_model.parents[1])
    model = with_record(native_model, tmp_path / "bad.safetensors", change)
    with pytest.raises(AgentError) as caught:
        load_agent(model)
    text = str(caught.value)
    assert "\n" not in text and message in text and str(model) in text, text
