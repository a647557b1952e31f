"""The `snakesim` command end to end on tiny runs with the Stable-Baselines3 trainer: train (both
networks), resume, evaluate, plot, replay, and its one-line errors (the native trainer's runs:
test_native.py). Every run is a few thousand timesteps with small rollouts, so this takes seconds."""

import csv
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from PIL import Image
from snakesim.cli import app as cli
from snakesim.cli import train as cli_train
from snakesim.runs import config as runconfig
from snakesim.runs.results import TrainingInterrupted
from snakesim.runs.rundir import EVAL_FIELDS
from snakesim.runs.sb3_trainer import Trainer
from stable_baselines3.common.callbacks import BaseCallback

REPO = Path(__file__).resolve().parents[2]

# Rollouts of 4 envs x 128 steps, episodes of at most 200 steps, 2 evaluation episodes.
TINY = {
    "trainer": "sb3",
    "joints": 3,
    "n_envs": 4,
    "timesteps": 1024,
    "eval_freq": 512,
    "eval_episodes": 2,
    "checkpoint_freq": 512,
    "device": "cpu",
    "torch_threads": 1,
    "ppo": {"n_steps": 128, "batch_size": 128, "n_epochs": 2},
    "env": {"max_episode_steps": 200},
}


def run_cli(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def tiny_yaml(tmp_path_factory):
    path = tmp_path_factory.mktemp("config") / "tiny.yaml"
    path.write_text(yaml.safe_dump(TINY))
    return path


@pytest.fixture(scope="module")
def small_run(tmp_path_factory, tiny_yaml):
    run_dir = tmp_path_factory.mktemp("runs") / "small"
    code = cli.main(
        ["train", "--config", str(tiny_yaml), "--arch", "small", "--run-dir", str(run_dir), "--no-progress"]
    )
    assert code == 0
    return run_dir


def test_train_writes_the_run_directory(small_run, tiny_yaml):
    names = {p.name for p in small_run.iterdir()}
    assert {"config.yaml", "versions.json", "evaluations.csv", "model.zip", "tb", "checkpoints"} <= names
    config = runconfig.load(small_run / "config.yaml")
    assert config == runconfig.resolve({**yaml.safe_load(tiny_yaml.read_text()), "arch": "small"})
    assert config["eval_seed"] == config["seed"] + runconfig.EVAL_SEED_OFFSET, "the seeds are recorded"
    versions = json.loads((small_run / "versions.json").read_text())
    assert set(versions) == {"snakesim", "stable_baselines3", "torch", "gymnasium", "numpy", "python"}
    rows = read_csv(small_run / "evaluations.csv")
    assert list(rows[0]) == list(EVAL_FIELDS)
    assert [int(r["timesteps"]) for r in rows] == [512, 1024], (
        "every eval_freq timesteps; the last is the end"
    )
    for row in rows:
        assert 0.0 <= float(row["success_rate"]) <= 1.0
        assert float(row["mean_return"]) < 0 and float(row["std_return"]) >= 0 and float(row["wall_time"]) > 0
    assert list((small_run / "tb").glob("PPO_1/events.out.tfevents.*")), "TensorBoard logs"
    assert sorted(p.name for p in (small_run / "checkpoints").glob("*.zip")) == [
        "model_1024_steps.zip",
        "model_512_steps.zip",
    ]


def test_train_large_network(tmp_path, tiny_yaml, capsys):
    from snakesim.runs.policies import parameter_count
    from stable_baselines3 import PPO

    run_dir = tmp_path / "large"
    code, out, _ = run_cli(
        capsys,
        "train",
        "--config",
        tiny_yaml,
        "--arch",
        "large",
        "--timesteps",
        512,
        "--run-dir",
        run_dir,
        "--no-progress",
    )
    assert code == 0
    assert "timesteps/s" in out
    model = PPO.load(run_dir / "model.zip", device="cpu")
    assert type(model.policy.features_extractor).__name__ == "SharedMlp"
    assert parameter_count(model.policy) == 42_759  # shared 128-128 on 8 inputs, heads 64-64, 3 joints
    assert len(read_csv(run_dir / "evaluations.csv")) == 1


class InterruptAt(BaseCallback):
    def __init__(self, timesteps):
        super().__init__()
        self.at = timesteps

    def _on_step(self):
        if self.num_timesteps >= self.at:
            raise KeyboardInterrupt
        return True


def test_interrupt_saves_and_resume_continues(tmp_path, tiny_yaml, capsys):
    run_dir = tmp_path / "run"
    # With VecNormalize: its statistics are saved and restored with the model.
    overrides = {
        **yaml.safe_load(tiny_yaml.read_text()),
        "eval_freq": 256,
        "checkpoint_freq": 0,
        "normalize": True,
    }
    trainer = Trainer(overrides, run_dir, progress=False, callbacks=[InterruptAt(600)])
    with pytest.raises(TrainingInterrupted) as stop:
        trainer.run()
    assert stop.value.timesteps == 600 and stop.value.path.is_file()
    assert (run_dir / "model.zip").is_file(), "Ctrl-C leaves a usable model"
    assert (run_dir / "vecnormalize.pkl").is_file() and (
        run_dir / "checkpoints/vecnormalize_600_steps.pkl"
    ).is_file()
    before = [int(r["timesteps"]) for r in read_csv(run_dir / "evaluations.csv")]
    assert before == [256, 512]

    code, out, err = run_cli(capsys, "train", "--run-dir", run_dir, "--resume", "--no-progress")
    assert code == 0, err
    assert "resuming from 600" in out
    after = [int(r["timesteps"]) for r in read_csv(run_dir / "evaluations.csv")]
    assert after[:2] == before and after[2:] == [768, 1024, 1112], "appended, from the checkpoint on"
    from stable_baselines3 import PPO

    assert PPO.load(run_dir / "model.zip", device="cpu").num_timesteps == 1112

    code, out, err = run_cli(capsys, "evaluate", run_dir, "--episodes", 2, "--json", "-")
    assert code == 0 and json.loads(out)["episodes"] == 2, err

    code, _, err = run_cli(capsys, "train", "--run-dir", run_dir, "--resume", "--joints", 4)
    assert code == 1 and "cannot change joints when resuming" in err
    code, _, err = run_cli(capsys, "train", "--run-dir", run_dir, "--resume")
    assert code == 1 and "already has 1112 timesteps" in err


def test_evaluate(small_run, tmp_path, capsys):
    out_json = tmp_path / "eval.json"
    code, out, err = run_cli(capsys, "evaluate", small_run, "--episodes", 3, "--seed", 5, "--json", out_json)
    assert code == 0, err
    for name in ("success rate", "mean return", "mean steps to goal", "mean speed"):
        assert name in out
    report = json.loads(out_json.read_text())
    assert report["episodes"] == 3 and len(report["per_episode"]) == 3
    assert 0.0 <= report["success_rate"] <= 1.0
    assert report["joints"] == 3 and report["preset"] == "paper" and report["arch"] == "small"
    assert report["mean_return"] < 0 and report["mean_speed"] >= 0
    assert {"mean_steps_to_goal", "std_return", "mean_seconds_to_goal"} <= set(report)
    # Same seed, same episodes; JSON alone on stdout with --json -.
    code, out, _ = run_cli(capsys, "evaluate", small_run, "--episodes", 3, "--seed", 5, "--json", "-")
    assert code == 0 and json.loads(out)["mean_return"] == report["mean_return"]
    # A bare zip: joints from the model, preset given.
    code, out, _ = run_cli(capsys, "evaluate", small_run / "model.zip", "--episodes", 1, "--json", "-")
    assert code == 0 and json.loads(out)["joints"] == 3


def test_plot_groups_seeds(small_run, tmp_path, capsys):
    # A second seed of the same experiment (its curve shifted), and a run of another experiment.
    other_seed = tmp_path / "seed2"
    shutil.copytree(small_run, other_seed)
    config = runconfig.load(other_seed / "config.yaml")
    runconfig.save({**config, "seed": 7, "eval_seed": 1007}, other_seed / "config.yaml")
    rows = read_csv(small_run / "evaluations.csv")
    with open(other_seed / "evaluations.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=EVAL_FIELDS)
        writer.writeheader()
        writer.writerows({**r, "mean_return": float(r["mean_return"]) + 100} for r in rows)
    other_exp = tmp_path / "joints4"
    shutil.copytree(small_run, other_exp)
    runconfig.save({**config, "joints": 4}, other_exp / "config.yaml")

    fig = tmp_path / "fig3.png"
    code, out, err = run_cli(
        capsys, "plot", small_run, other_seed, other_exp, "--out", fig, "--title", "Figure 3"
    )
    assert code == 0, err
    assert "PPO-small, 3 joints (paper), 2 runs" in out and "PPO-small, 4 joints (paper)" in out
    with Image.open(fig) as image:  # two panels by default: the return, and below it the success rate
        assert image.format == "PNG" and image.size == (1050, 1050)
    svg = tmp_path / "fig3.svg"
    code, _, _ = run_cli(capsys, "plot", small_run, "--out", svg)
    labels = ("mean evaluation return", "evaluation success rate")
    panels = [t for t in labels if f"<!-- {t} -->" in svg.read_text()]
    assert code == 0 and panels == ["mean evaluation return", "evaluation success rate"]
    code, _, _ = run_cli(capsys, "plot", small_run, "--out", fig, "--metric", "mean_return")
    with Image.open(fig) as image:  # one metric, one panel
        assert code == 0 and image.size == (1050, 675)
    code, out, _ = run_cli(capsys, "plot", small_run, other_seed, "--out", fig, "--group", "none")
    assert code == 0 and out.count("PPO-small") == 2
    # Labels of one's own, one per line in the order drawn; a count that does not match is one line.
    code, out, _ = run_cli(
        capsys, "plot", small_run, other_seed, other_exp, "--out", fig, "--label", "three", "--label", "four"
    )
    assert code == 0 and out.strip().endswith("three, 2 runs; four")
    code, _, err = run_cli(capsys, "plot", small_run, other_exp, "--out", fig, "--label", "one")
    assert code == 1 and err.strip().endswith(
        "1 labels for 2 lines (PPO-small, 3 joints (paper); PPO-small, 4 joints (paper))"
    )


def test_replay_figure_and_gif(small_run, tmp_path, capsys):
    png, gif = tmp_path / "motion.png", tmp_path / "motion.gif"
    code, out, err = run_cli(
        capsys,
        "replay",
        small_run,
        "--seconds",
        0.5,
        "--fps",
        10,
        "--out",
        png,
        "--out",
        gif,
        "--deterministic",
    )
    assert code == 0, err
    assert "replayed 0.50 s (120 steps)" in out
    with Image.open(png) as image:
        assert image.format == "PNG" and image.size[0] > 1000 and image.size[1] > 400
    with Image.open(gif) as image:
        assert image.format == "GIF" and image.n_frames == 6, "frames at t = 0, 0.1, ..., 0.5 s"
        assert image.size == (480, 480) and image.info["duration"] == 100


def test_mp4_needs_ffmpeg(small_run, tmp_path, capsys, monkeypatch):
    import snakesim.viewer.replay

    monkeypatch.setattr(snakesim.viewer.replay.shutil, "which", lambda name: None)
    code, _, err = run_cli(capsys, "replay", small_run, "--seconds", 0.1, "--out", tmp_path / "m.mp4")
    assert code == 1 and "mp4 needs ffmpeg" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "m.mp4").exists()


def bad_inputs(tmp_path, small_run):
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    malformed = tmp_path / "bad.yaml"
    malformed.write_text("joints: [5\n")
    unknown_key = tmp_path / "unknown.yaml"
    unknown_key.write_text("joints: 5\nlearning_rate: 0.1\n")
    return {
        "missing run dir": (["evaluate", tmp_path / "nope"], 1, "does not exist"),
        "not a model": (
            ["evaluate", a_file],
            1,
            "is neither a snakesim model (safetensors) nor a Stable-Baselines3 model (zip)",
        ),
        "wrong joints": (["evaluate", small_run, "--joints", 5], 1, "trained with joints 3, not 5"),
        "unknown arch": (["train", "--arch", "huge"], 2, "invalid choice: 'huge'"),
        "unknown option": (["train", "--bogus"], 2, "unrecognized arguments: --bogus"),
        "malformed yaml": (
            ["train", "--config", malformed, "--run-dir", tmp_path / "r1"],
            1,
            "bad.yaml: not valid YAML (line 2",
        ),
        "unknown yaml key": (
            ["train", "--config", unknown_key, "--run-dir", tmp_path / "r2"],
            1,
            "learning_rate: unknown field `learning_rate`",
        ),
        "missing yaml": (["train", "--config", tmp_path / "none.yaml"], 1, "does not exist"),
        "existing run dir": (["train", "--run-dir", small_run], 1, "already exists and is not empty"),
        "unwritable run dir": (
            ["train", "--run-dir", a_file / "run", "--timesteps", 8],
            1,
            "cannot write to run directory",
        ),
        "resume nothing": (
            ["train", "--run-dir", tmp_path / "empty", "--resume"],
            1,
            f"cannot resume {tmp_path / 'empty'}: no such directory",
        ),
        "unwritable plot": (["plot", small_run, "--out", a_file / "fig.png"], 1, "does not exist"),
        "plot format": (
            ["plot", small_run, "--out", tmp_path / "fig.jpg"],
            1,
            "expected a .png, .pdf or .svg",
        ),
        "plot no evaluations": (["plot", tmp_path, "--out", tmp_path / "f.png"], 1, "has no evaluations.csv"),
        "unwritable replay": (["replay", small_run, "--out", a_file / "m.gif"], 1, "does not exist"),
        "replay format": (["replay", small_run, "--out", tmp_path / "m.avi"], 1, "unknown format .avi"),
        "unwritable json": (["evaluate", small_run, "--json", a_file / "e.json"], 1, "does not exist"),
        "bad seconds": (
            ["replay", small_run, "--out", tmp_path / "m.gif", "--seconds", -1],
            2,
            "positive number",
        ),
        "bad set": (
            ["train", "--set", "ppo.gamma=2", "--run-dir", tmp_path / "r3"],
            1,
            "ppo.gamma: must be in [0, 1], got 2",
        ),
    }


CASES = [
    "missing run dir", "not a model", "wrong joints", "unknown arch", "unknown option", "malformed yaml",
    "unknown yaml key", "missing yaml", "existing run dir", "unwritable run dir", "resume nothing",
    "unwritable plot", "plot format", "plot no evaluations", "unwritable replay", "replay format",
    "unwritable json", "bad seconds", "bad set",
]  # fmt: skip


@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_one_line_and_non_zero(case, tmp_path, small_run, capsys):
    argv, expected_code, message = bad_inputs(tmp_path, small_run)[case]
    try:
        code = cli.main([str(a) for a in argv])
    except SystemExit as stop:  # argparse's usage errors
        code = stop.code
    out, err = capsys.readouterr()
    assert code == expected_code
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("snakesim") and "error:" in lines[0], err
    assert message in lines[0]
    assert "Traceback" not in err


def test_console_script_and_module(repo):
    tomllib = pytest.importorskip("tomllib")
    scripts = tomllib.loads((repo / "snake-py" / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts == {"snakesim": "snakesim.cli:main"}
    result = subprocess.run(
        [sys.executable, "-m", "snakesim.cli", "evaluate", "/nonexistent/run"], capture_output=True, text=True
    )
    assert result.returncode == 1
    expected = "/nonexistent/run does not exist (expected a run directory or a model .zip)"
    assert result.stderr == f"snakesim evaluate: error: {expected}\n"
    result = subprocess.run([sys.executable, "-m", "snakesim", "--help"], capture_output=True, text=True)
    assert result.returncode == 0 and "train" in result.stdout and "replay" in result.stdout


def test_cube_poses(tmp_path):
    import numpy as np
    import snakesim

    env = snakesim.SnakeEnv(joints=3)
    with pytest.raises(RuntimeError):
        env.cube_poses()
    env.reset(seed=0, options={"start": (1.0, 2.0, 0.25, 0.0), "goal": (3.0, 4.0)})
    poses = env.cube_poses()
    assert poses.shape == (4, 7) and poses.dtype == np.float64
    assert abs(poses[0, 0] - 1.0) < 1e-3 and abs(poses[0, 1] - 2.0) < 1e-3, "the head first"
    assert np.all(np.diff(poses[:, 1]) > 0.5), "the tail along +y"
    assert env.goal == (3.0, 4.0) and env.half_extent == 0.25


def test_shipped_configs_parse_as_train_options(repo):
    # The shipped configs are accepted by the train command's parser as they are.
    for path in sorted((repo / "snake-py" / "configs").glob("*.yaml")):
        args = cli.build_parser().parse_args(["train", "--config", str(path)])
        overrides = cli_train._train_overrides(args)
        assert runconfig.resolve(overrides) == runconfig.resolve(runconfig.load_yaml(path))


def test_mp4_through_ffmpeg(small_run, tmp_path, capsys, monkeypatch):
    # A stand-in ffmpeg that counts the raw RGB bytes it is sent (no encoder is needed on this machine).
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    fake = bin_dir / "ffmpeg"
    fake.write_text(
        f"#!{sys.executable}\n"
        "import sys\n"
        "data = sys.stdin.buffer.read()\n"
        "size = sys.argv[sys.argv.index('-s') + 1]\n"
        "open(sys.argv[-1], 'w').write(f'{len(data)} {size}')\n"
    )
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}:{os.environ['PATH']}")
    out = tmp_path / "m.mp4"
    code, stdout, err = run_cli(capsys, "replay", small_run, "--seconds", 0.25, "--fps", 8, "--out", out)
    assert code == 0, err
    assert "(3 frames at 8 fps)" in stdout
    assert out.read_text() == f"{3 * 480 * 480 * 3} 480x480"


def _long_flags(help_text: str) -> set[str]:
    return set(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", help_text))


def test_snakesim_train_offers_every_flag_of_snake_cli_train(capsys):
    exe = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release" / "snake-cli"
    if not exe.is_file():
        pytest.skip(f"{exe} is not built")
    rust = subprocess.run([exe, "train", "--help"], capture_output=True, text=True, check=True).stdout
    with pytest.raises(SystemExit):
        cli.main(["train", "--help"])
    python = capsys.readouterr().out
    assert _long_flags(rust) - {"--help"} <= _long_flags(python)
    # The same default run directory, from snake-rl, in both.
    assert "runs/ppo-ARCH-JOINTS-PRESET-seedSEED" in rust
    assert "runs/ppo-ARCH-JOINTS-" in python


def test_docs_cli_md_is_current():
    """docs/cli.md is the two commands' own --help (scripts/cli_docs.py), so it cannot drift."""
    repo = Path(__file__).resolve().parents[2]
    target = Path(os.environ.get("CARGO_TARGET_DIR", repo / "target"))
    if not (target / "release" / "snake-cli").is_file():
        pytest.skip("snake-cli is not built (bash scripts/setup builds it)")
    done = subprocess.run(
        [sys.executable, str(repo / "scripts" / "cli_docs.py"), "--check"], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
