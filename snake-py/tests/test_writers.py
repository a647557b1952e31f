"""One writer per run directory and sweep folder, nothing left behind, and saying what happened:
two trainers on one run, a killed writer, skipped checkpoints, impossible model metadata, files of the
wrong kind, Ctrl-C, and the temporary files of every command."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest
import yaml
from safetensors import safe_open
from safetensors.numpy import load_file, save_file
from snakesim import _core, agents
from snakesim.cli import app as cli
from snakesim.runs import rundir
from snakesim.runs.native import NativeTrainer
from snakesim.runs.rundir import RunDirError
from snakesim.runs.sb3_trainer import Trainer
from snakesim.sweeps import plan as sweep

REPO = Path(__file__).resolve().parents[2]

# A native run whose rollouts take a fraction of a second: 4 envs x 128 steps, checkpoints every 1024.
TINY = {
    "trainer": "native",
    "joints": 3,
    "n_envs": 4,
    "timesteps": 4096,
    "eval_freq": 1024,
    "eval_episodes": 1,
    "checkpoint_freq": 1024,
    "threads": 1,
    "ppo": {"n_steps": 128, "batch_size": 64, "n_epochs": 1},
    "env": {"max_episode_steps": 100},
}
TINY_SB3 = {
    **TINY,
    "trainer": "sb3",
    "timesteps": 1024,
    "eval_freq": 512,
    "checkpoint_freq": 512,
    "n_envs": 2,
}
TINY_SB3.pop("threads")
TINY_SB3["torch_threads"] = 1
TINY_SB3["device"] = "cpu"


@pytest.fixture(scope="module")
def snake_cli() -> Path:
    exe = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release" / "snake-cli"
    if not exe.is_file():
        pytest.skip(f"{exe} is not built (cargo build --release -p snake-cli)")
    return exe


def write_yaml(path: Path, config) -> Path:
    path.write_text(yaml.safe_dump(config))
    return path


def evaluation_steps(run_dir: Path) -> list[int]:
    with open(run_dir / "evaluations.csv", newline="") as f:
        return [int(float(row["timesteps"])) for row in csv.DictReader(f)]


def wait_for(condition, seconds: float = 60.0) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.05)


# -- 1. one writer per run directory ---------------------------------------------------------------
def test_a_second_writer_is_refused_at_once_and_the_first_run_stays_its_own(snake_cli, tmp_path):
    """The issue's case: `snake-cli train` running, and `train --resume` on the same run directory in
    another terminal (here also a fresh `train` there, and both through `snakesim`)."""
    config = write_yaml(tmp_path / "long.yaml", {**TINY, "timesteps": 60 * 1024, "eval_freq": 2048})
    run_dir = tmp_path / "run"
    first = subprocess.Popen(
        [snake_cli, "train", "--config", config, "--run-dir", run_dir, "--no-progress"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    wait_for(lambda: len(rundir.checkpoints(run_dir, native=True)) >= 2)
    seconds = []
    for argv in (
        [snake_cli, "train", "--run-dir", run_dir, "--resume", "--timesteps", "200000", "--no-progress"],
        [snake_cli, "train", "--config", config, "--run-dir", run_dir, "--no-progress"],
        [
            sys.executable,
            "-m",
            "snakesim",
            "train",
            "--run-dir",
            run_dir,
            "--resume",
            "--timesteps",
            "200000",
        ],
        [sys.executable, "-m", "snakesim", "train", "--config", config, "--run-dir", run_dir],
    ):
        start = time.monotonic()
        second = subprocess.run(argv, capture_output=True, text=True, timeout=60)
        seconds.append(time.monotonic() - start)
        assert second.returncode == 1, second
        lines = second.stderr.strip().splitlines()
        assert len(lines) == 1, second.stderr
        assert f"run directory {run_dir} is being written by another process: pid {first.pid} on " in lines[0]
        assert "snake-cli train" in lines[0]
    out, err = first.communicate(timeout=300)
    assert first.returncode == 0, err
    # The refusal is the time to start the command: snake-cli's is immediate.
    assert seconds[0] < 1.0 and seconds[1] < 1.0, seconds
    steps = evaluation_steps(run_dir)
    assert steps == sorted(set(steps)), "no evaluation twice"
    assert steps[-1] == 60 * 1024
    checkpoints = rundir.checkpoints(run_dir, native=True)
    assert [s for s, _ in checkpoints] == [1024 * k for k in range(1, 61)], "only the first run's"
    for steps_, path in checkpoints:
        assert json.loads(path.with_suffix(".json").read_text())["timesteps"] == steps_


def test_a_killed_writer_leaves_a_run_that_resumes_at_once(snake_cli, tmp_path):
    config = write_yaml(tmp_path / "long.yaml", {**TINY, "timesteps": 10_000_000, "eval_freq": 2048})
    run_dir = tmp_path / "run"
    first = subprocess.Popen(
        [snake_cli, "train", "--config", config, "--run-dir", run_dir, "--no-progress"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wait_for(lambda: len(rundir.checkpoints(run_dir, native=True)) >= 3)
    first.send_signal(signal.SIGKILL)
    first.wait(timeout=30)
    last = rundir.checkpoints(run_dir, native=True)[-1][0]
    resumed = subprocess.run(
        [
            snake_cli,
            "train",
            "--run-dir",
            run_dir,
            "--resume",
            "--timesteps",
            str(last + 2048),
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert resumed.returncode == 0, resumed.stderr
    assert f"(resuming from {last})" in resumed.stdout
    steps = evaluation_steps(run_dir)
    assert steps == sorted(set(steps)) and steps[-1] == last + 2048


def test_trainers_in_one_process_take_turns_too(tmp_path):
    run_dir = tmp_path / "run"
    holder = NativeTrainer(TINY, run_dir, progress=False)
    assert (run_dir / _core.LOCK_FILE).is_file() and holder.lock.held
    for make in (
        lambda: NativeTrainer(TINY, run_dir, resume=True, progress=False),
        lambda: NativeTrainer(TINY, run_dir, progress=False),
        lambda: Trainer(TINY_SB3, run_dir, progress=False),
    ):
        with pytest.raises(RunDirError, match=f"pid {os.getpid()} on "):
            make()
    holder.run()
    assert not holder.lock.held, "let go when training ends"
    resumed = NativeTrainer({"timesteps": 8192}, run_dir, resume=True, progress=False)
    assert resumed.resume_from[0] == 4096
    resumed.lock.release()


def test_a_new_run_may_use_a_folder_holding_only_a_lock_file(tmp_path):
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / _core.LOCK_FILE).write_text("pid 1 on elsewhere since 0: an old writer\n")
    NativeTrainer(TINY, run_dir, progress=False).run()
    assert (run_dir / "model.safetensors").is_file()


def test_a_sweep_folder_has_one_writer(tmp_path):
    pytest.importorskip("ray")
    from snakesim.sweeps import sweep as sweep_runner

    out = tmp_path / "sweep"
    trials = sweep.plan({"tiny": dict(TINY)}, {}, 1, 1)
    manifest = sweep.new_manifest("sweep", trials, configs=["tiny.yaml"], grid={}, seeds=1, set=[])
    manifest.update(cpus_per_trial=1, max_failures=0)
    with sweep.start_folder(out, manifest):
        with pytest.raises(sweep.SweepError, match=f"folder {out} is being written by another process"):
            sweep_runner.resume_sweep(out)
        start = time.monotonic()
        with pytest.raises(sweep.SweepError, match=r"\(waited 0\.5 s\)"):
            sweep.lock_folder(out, 0.5)
        assert time.monotonic() - start >= 0.5
    assert sweep.lock_folder(out).held


# -- 3. say what happened ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def native_run(tmp_path_factory):
    run_dir = tmp_path_factory.mktemp("writers") / "run"
    NativeTrainer({**TINY, "normalize": True}, run_dir, progress=False).run()
    return run_dir


def _copy(run_dir: Path, tmp_path: Path) -> Path:
    target = tmp_path / "copy"
    shutil.copytree(run_dir, target, ignore=shutil.ignore_patterns(_core.LOCK_FILE))
    return target


def test_a_corrupt_checkpoint_is_skipped_and_named_on_resume(native_run, tmp_path, capsys):
    run_dir = _copy(native_run, tmp_path)
    newest = run_dir / "checkpoints" / "model_4096_steps.safetensors"
    newest.write_bytes(newest.read_bytes()[:500])
    code = cli.main(["train", "--run-dir", str(run_dir), "--resume", "--timesteps", "5120", "--no-progress"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "(resuming from 3,072)" in out
    notes = [line for line in err.splitlines() if line.startswith("note: ")]
    assert notes == [
        f"note: skipped a checkpoint: {newest} is not a snakesim model: corrupt or truncated "
        "safetensors file (invalid header length)"
    ], err
    assert evaluation_steps(run_dir) == [1024, 2048, 3072, 4096, 5120]


def test_no_loadable_checkpoint_is_one_line(native_run, tmp_path, capsys):
    run_dir = _copy(native_run, tmp_path)
    for _, path in rundir.checkpoints(run_dir, native=True):
        path.write_bytes(b"garbage")
    code = cli.main(["train", "--run-dir", str(run_dir), "--resume", "--timesteps", "8192", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 1
    assert err.count("\n") == 1 and "none of its checkpoints loads (skipped a checkpoint: " in err, err


def test_an_sb3_checkpoint_with_a_corrupt_note_is_skipped_and_named(tmp_path, capsys):
    run_dir = tmp_path / "sb3"
    Trainer(TINY_SB3, run_dir, progress=False).run()
    note = run_dir / "checkpoints" / "model_1024_steps.json"
    note.write_text("{garbage")
    code = cli.main(["train", "--run-dir", str(run_dir), "--resume", "--timesteps", "1536", "--no-progress"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "(resuming from 512)" in out
    assert f"note: skipped a checkpoint: {note} is corrupt (JSONDecodeError: " in err, err


def _rewrite(path: Path, target: Path, meta=None, tensors=None) -> Path:
    with safe_open(str(path), "np") as f:
        metadata = dict(f.metadata())
    data = load_file(str(path))
    metadata.update(meta or {})
    data.update(tensors or {})
    save_file(data, str(target), metadata=metadata)
    return target


@pytest.mark.parametrize(
    ("meta", "tensor", "message"),
    [
        ({"obs_rms.count": "nan"}, None, "metadata 'obs_rms.count' = NaN is out of range"),
        ({"obs_rms.count": "-5"}, None, "metadata 'obs_rms.count' = -5 is out of range"),
        ({"obs_rms.count": "inf"}, None, "metadata 'obs_rms.count' = inf is out of range"),
        (None, "obs_rms.var", "tensor 'obs_rms.var' holds negative variances"),
    ],
)
def test_impossible_model_metadata_is_refused_naming_the_key(
    native_run, tmp_path, capsys, meta, tensor, message
):
    model = native_run / "model.safetensors"
    tensors = None
    if tensor is not None:
        values = load_file(str(model))[tensor].copy()
        values[0] = -1.0
        tensors = {tensor: values}
    bad = _rewrite(model, tmp_path / "bad.safetensors", meta, tensors)
    assert cli.main(["evaluate", str(bad), "--episodes", "1"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err


def test_impossible_checkpoint_metadata_is_refused_on_resume(native_run, tmp_path, capsys):
    run_dir = _copy(native_run, tmp_path)
    for steps, path in rundir.checkpoints(run_dir, native=True):
        _rewrite(path, path, {"wall_time": "-1" if steps % 2048 else "nan", "normalize.gamma": "2"})
    code = cli.main(["train", "--run-dir", str(run_dir), "--resume", "--timesteps", "8192", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 1
    assert "metadata 'normalize.gamma' = 2 is out of range" in err, err


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        (
            "model.pt",
            b"garbage\n",
            "is neither a snakesim model (safetensors) nor a Stable-Baselines3 model (zip)",
        ),
        (
            "model.bin",
            b"\x10\x00\x00\x00\x00\x00\x00\x00{broken",
            "is not a snakesim model: corrupt or truncated",
        ),
        ("model.pt", b"PK\x03\x04broken", "is not a Stable-Baselines3 model zip"),
    ],
)
def test_a_model_file_is_judged_by_its_content_and_named(tmp_path, capsys, name, content, message):
    path = tmp_path / name
    path.write_bytes(content)
    assert cli.main(["evaluate", str(path)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{path} " in err and message in err, err


def test_a_snakesim_model_with_another_name_still_loads(native_run, tmp_path):
    path = tmp_path / "policy.weights"
    shutil.copy(native_run / "model.safetensors", path)
    assert agents.load_agent(path).kind == "native"


def test_ctrl_c_in_snake_cli_says_what_was_saved_not_an_error(snake_cli, tmp_path):
    config = write_yaml(tmp_path / "long.yaml", {**TINY, "timesteps": 10_000_000, "eval_freq": 0})
    run_dir = tmp_path / "run"
    process = subprocess.Popen(
        [snake_cli, "train", "--config", config, "--run-dir", run_dir, "--no-progress"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    wait_for(lambda: len(rundir.checkpoints(run_dir, native=True)) >= 1)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert "error" not in err
    steps = rundir.checkpoints(run_dir, native=True)[-1][0]
    assert err.strip() == (
        f"interrupted at {steps} timesteps; saved {run_dir}/checkpoints/model_{steps}_steps.safetensors and "
        f"{run_dir}/model.safetensors; continue with: snake-cli train --run-dir {run_dir} --resume"
    )


# -- 2. nothing left behind ----------------------------------------------------------------------------
def test_no_command_leaves_files_outside_what_it_was_asked_to_write(snake_cli, tmp_path):
    """Every command with its own empty TMPDIR and working directory: afterwards TMPDIR is empty again
    and the working directory holds only the outputs named on the command line."""
    scratch, work = tmp_path / "tmp", tmp_path / "work"
    scratch.mkdir()
    work.mkdir()
    write_yaml(work / "native.yaml", TINY)
    write_yaml(work / "sb3.yaml", TINY_SB3)
    env = {**os.environ, "TMPDIR": str(scratch)}
    env.pop("TORCHINDUCTOR_CACHE_DIR", None)
    snakesim = [sys.executable, "-m", "snakesim"]
    commands = [
        [snake_cli, "train", "--config", "native.yaml", "--run-dir", "cli-run", "--no-progress"],
        [*snakesim, "train", "--config", "native.yaml", "--run-dir", "native-run", "--no-progress"],
        [*snakesim, "train", "--config", "sb3.yaml", "--run-dir", "sb3-run", "--no-progress"],
        [*snakesim, "train", "--run-dir", "sb3-run", "--resume", "--timesteps", "1536", "--no-progress"],
        [*snakesim, "evaluate", "sb3-run", "--episodes", "1", "--json", "eval.json"],
        [*snakesim, "evaluate", "native-run", "--episodes", "1"],
        [*snakesim, "export", "native-run", "--sb3", "exported.zip"],
        [*snakesim, "evaluate", "exported.zip", "--episodes", "1", "--joints", "3"],
        [*snakesim, "plot", "native-run", "sb3-run", "--out", "curves.png"],
        [*snakesim, "replay", "native-run", "--out", "replay.png"],
        [snake_cli, "run", "--joints", "3", "--seconds", "1", "--output", "gait.csv"],
    ]
    for argv in commands:
        result = subprocess.run(argv, cwd=work, env=env, capture_output=True, text=True, timeout=300)
        assert result.returncode == 0, (argv, result.stderr)
        assert sorted(p.name for p in scratch.iterdir()) == [], argv
    expected = {"native.yaml", "sb3.yaml", "cli-run", "native-run", "sb3-run", "eval.json", "exported.zip"}
    expected |= {"curves.png", "replay.png", "gait.csv"}
    assert {p.name for p in work.iterdir()} == expected
    counts = Counter(p.name.startswith(".") for p in work.rglob("*"))
    assert counts[True] == 0, "no temporary files left in the run directories"
