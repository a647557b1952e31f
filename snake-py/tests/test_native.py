"""The native trainer (snake-rl) through the `snakesim` command and package: the run directory,
TensorBoard, evaluate, plot, replay, export to Stable-Baselines3, Ctrl-C and resume, bad input."""

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from snakesim import agents
from snakesim.cli import app as cli
from snakesim.runs import config as runconfig
from snakesim.runs import rundir
from snakesim.runs.rundir import EVAL_FIELDS

# Rollouts of 4 envs x 128 steps, episodes of at most 200 steps, 2 evaluation episodes: about a second.
TINY = {
    "trainer": "native",
    "joints": 3,
    "n_envs": 4,
    "timesteps": 2048,
    "eval_freq": 1024,
    "eval_episodes": 2,
    "checkpoint_freq": 1024,
    "threads": 2,
    "ppo": {"n_steps": 128, "batch_size": 64, "n_epochs": 2},
    "env": {"max_episode_steps": 200},
}


def run_cli(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def write_yaml(path, config):
    path.write_text(yaml.safe_dump(config))
    return path


def train(base, config):
    """``snakesim train`` of ``config`` into ``base/run``; the run directory."""
    run_dir = base / "run"
    argv = ["train", "--config", str(write_yaml(base / "config.yaml", config)), "--run-dir", str(run_dir)]
    assert cli.main([*argv, "--no-progress"]) == 0
    return run_dir


@pytest.fixture(scope="module")
def native_run(tmp_path_factory):
    return train(tmp_path_factory.mktemp("native"), TINY)


@pytest.fixture(scope="module")
def normalized_run(tmp_path_factory):
    config = {**TINY, "normalize": True, "eval_freq": 0, "checkpoint_freq": 0}
    return train(tmp_path_factory.mktemp("native-normalized"), config)


def test_the_run_directory_is_every_snakesim_run_s(native_run):
    names = {p.name for p in native_run.iterdir()}
    assert {
        "config.yaml",
        "versions.json",
        "evaluations.csv",
        "model.safetensors",
        "tb",
        "checkpoints",
    } <= names
    config = runconfig.load(native_run / "config.yaml")
    assert config["trainer"] == "native" and config["eval_seed"] == 42 + runconfig.EVAL_SEED_OFFSET
    versions = json.loads((native_run / "versions.json").read_text())
    assert versions["trainer"] == "native" and {"snakesim", "python", "numpy"} <= set(versions)
    with open(native_run / "evaluations.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert tuple(rows[0]) == EVAL_FIELDS, "the same columns as SB3 runs"
    assert [int(r["timesteps"]) for r in rows] == [1024, 2048]
    assert sorted(p.name for p in (native_run / "checkpoints").iterdir()) == [
        "model_1024_steps.json",
        "model_1024_steps.safetensors",
        "model_2048_steps.json",
        "model_2048_steps.safetensors",
    ]


def test_tensorboard_reads_the_native_scalars(native_run):
    # TensorBoard's own reader is the reference for the event files written in Rust.
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    events = EventAccumulator(str(native_run / "tb" / "PPO_1"))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert {"train/value_loss", "train/approx_kl", "train/std", "eval/mean_reward", "time/fps"} <= tags
    assert [e.step for e in events.Scalars("eval/success_rate")] == [1024, 2048]
    with open(native_run / "evaluations.csv", newline="") as f:
        evaluations = [float(r["mean_return"]) for r in csv.DictReader(f)]
    logged = [e.value for e in events.Scalars("eval/mean_reward")]
    assert np.allclose(logged, evaluations, rtol=1e-6), "TensorBoard and evaluations.csv agree"


def test_python_evaluation_repeats_the_trainers(native_run):
    # The trainer evaluates in Rust; snakesim evaluate runs the same protocol in Python: same numbers.
    agent = agents.load_agent(native_run)
    assert agent.kind == "native" and agent.joints == 3
    result = agents.evaluate(agent, episodes=2, seed=42 + runconfig.EVAL_SEED_OFFSET)
    with open(native_run / "evaluations.csv", newline="") as f:
        last = list(csv.DictReader(f))[-1]
    assert result["mean_return"] == pytest.approx(float(last["mean_return"]), rel=1e-12)
    assert result["success_rate"] == float(last["success_rate"])


def test_evaluate_plot_replay_work_on_native_runs(native_run, tmp_path, capsys):
    code, out, _ = run_cli(capsys, "evaluate", native_run, "--episodes", 3, "--json", "-")
    assert code == 0
    report = json.loads(out)
    assert report["episodes"] == 3 and 0.0 <= report["success_rate"] <= 1.0 and report["joints"] == 3
    code, out, _ = run_cli(capsys, "evaluate", native_run / "model.safetensors", "--episodes", 2)
    assert code == 0 and "native trainer" in out
    code, _, _ = run_cli(capsys, "plot", native_run, "--out", tmp_path / "fig.png")
    assert code == 0 and (tmp_path / "fig.png").stat().st_size > 10_000
    code, _, _ = run_cli(capsys, "replay", native_run, "--seconds", 0.5, "--out", tmp_path / "m.gif")
    assert code == 0 and (tmp_path / "m.gif").is_file()


def _observations(env_kwargs, count=300):
    from snakesim import SnakeEnv

    env = SnakeEnv(**env_kwargs)
    obs, _ = env.reset(seed=3)
    out = []
    rng = np.random.default_rng(0)
    for _ in range(count):
        out.append(obs)
        obs, _, terminated, truncated, _ = env.step(
            rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        )
        if terminated or truncated:
            obs, _ = env.reset()
    return np.array(out, dtype=np.float32)


def _assert_same_actions(ours, theirs):
    # float32 networks summed in different orders: the max-norm relative tolerance of the reference tests.
    scale = max(float(np.abs(theirs).max()), 1e-30)
    assert float(np.abs(ours - theirs).max()) <= 1e-5 * scale


def test_export_to_sb3_acts_as_the_native_policy(native_run, tmp_path, capsys):
    from stable_baselines3 import PPO

    out = tmp_path / "exported.zip"
    code, stdout, _ = run_cli(capsys, "export", native_run, "--sb3", out)
    assert code == 0 and out.is_file() and "load with PPO.load" in stdout
    agent = agents.load_agent(native_run)
    obs = _observations(agent.env_kwargs)
    model = PPO.load(out, device="cpu")
    theirs, _ = model.predict(obs, deterministic=True)
    _assert_same_actions(agent.act(obs, deterministic=True), theirs)
    # And snakesim evaluates the exported zip as the SB3 model it is.
    code, _, _ = run_cli(capsys, "evaluate", out, "--joints", 3, "--episodes", 2)
    assert code == 0


def test_export_carries_the_observation_statistics(normalized_run, tmp_path, capsys):
    from snakesim.envs.sb3 import SnakeVecEnv
    from snakesim.runs.export import vecnormalize_path
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    out = tmp_path / "normalized.zip"
    code, _, _ = run_cli(capsys, "export", normalized_run, "--sb3", out)
    assert code == 0 and vecnormalize_path(out).is_file()
    agent = agents.load_agent(normalized_run)
    obs = _observations(agent.env_kwargs)
    normalizer = VecNormalize.load(str(vecnormalize_path(out)), SnakeVecEnv(1, **agent.env_kwargs))
    theirs, _ = PPO.load(out, device="cpu").predict(normalizer.normalize_obs(obs), deterministic=True)
    _assert_same_actions(agent.act(obs, deterministic=True), theirs)


def test_ctrl_c_saves_and_resume_continues(tmp_path):
    config = write_yaml(tmp_path / "long.yaml", {**TINY, "timesteps": 50_000_000, "eval_freq": 0})
    run_dir = tmp_path / "run"
    command = [
        sys.executable,
        "-m",
        "snakesim",
        "train",
        "--config",
        str(config),
        "--run-dir",
        str(run_dir),
        "--no-progress",
    ]
    # SIGINT as a terminal sends it; the child must not inherit an ignored SIGINT (as background jobs do).
    process = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.monotonic() + 60
    while not (run_dir / "tb").is_dir() and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(1.0)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "interrupted at" in lines[0] and "--resume" in lines[0], err
    found = rundir.checkpoints(run_dir, native=True)
    assert found, "a checkpoint was saved"
    steps = found[-1][0]
    resumed = subprocess.run(
        [
            *command[:4],
            "--run-dir",
            str(run_dir),
            "--resume",
            "--timesteps",
            str(steps + 1024),
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert resumed.returncode == 0, resumed.stderr
    assert f"resuming from {steps:,}" in resumed.stdout


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["train", "--trainer", "native", "--set", "ppo.batch_size=1"], "ppo.batch_size: must be in [2,"),
        (["train", "--trainer", "native", "--threads", "100000"], "threads: must be in [1, 256]"),
        (["train", "--trainer", "native", "--set", "env.goal=[1e39, 0]"], "env.goal: must have |x| and |y|"),
        (["export", "{run}", "--sb3", "{tmp}/out.txt"], "expected a .zip file"),
        (["evaluate", "{tmp}/garbage.safetensors"], "corrupt or truncated safetensors file"),
        (["train", "--run-dir", "{run}", "--resume", "--seed", "3"], "cannot change seed when resuming"),
    ],
)
def test_bad_input_is_one_line(argv, message, native_run, tmp_path, capsys):
    (tmp_path / "garbage.safetensors").write_bytes(b"\x00" * 40)
    argv = [a.format(run=native_run, tmp=tmp_path) for a in argv]
    if argv[0] == "train" and "--run-dir" not in argv:
        argv += ["--run-dir", str(tmp_path / "new")]
    code, _, err = run_cli(capsys, *argv)
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and lines[0].startswith("snakesim"), err
    assert message in lines[0], lines[0]
    assert not (tmp_path / "new").exists(), "nothing is created for a refused run"


def test_a_native_run_is_not_resumed_by_sb3(native_run, capsys):
    code, _, err = run_cli(capsys, "train", "--run-dir", native_run, "--resume", "--trainer", "sb3")
    assert code == 1 and "cannot change trainer when resuming" in err


def test_environment_variables_do_not_leak(monkeypatch):
    # The native trainer takes its threads from the configuration only.
    monkeypatch.setenv("RAYON_NUM_THREADS", "1")
    assert runconfig.validate({"threads": 2})["threads"] == 2
    assert os.environ["RAYON_NUM_THREADS"] == "1"


def test_widths_and_log_std_init_of_ones_own(tmp_path, capsys):
    """``arch`` as SB3's net_arch (with a trunk) and ``log_std_init``: the native run builds, saves and
    loads that network, SB3 builds the same one from the same config, and the export acts alike."""
    from snakesim.runs.policies import policy_kwargs
    from stable_baselines3 import PPO

    arch = {"shared": [24], "pi": [32, 16], "vf": [8]}
    # A learning rate so small that training leaves log_std where it started (Adam moves a parameter
    # by about the learning rate per step): what remains is the initialisation.
    config = {**TINY, "arch": arch, "log_std_init": -0.7, "ppo": {**TINY["ppo"], "learning_rate": 1e-12}}
    run_dir = train(tmp_path, config)
    assert runconfig.load(run_dir / "config.yaml")["arch"] == arch
    agent = agents.load_agent(run_dir)
    assert agent.arch == "shared [24], pi [32, 16], vf [8]" and agent.policy.net_arch == arch
    tensors = agent.policy.tensors()
    np.testing.assert_allclose(tensors["log_std"], -0.7, atol=1e-6)
    # SB3 (the reference) builds the same tensors from the same keys.
    env_kwargs = runconfig.env_kwargs(runconfig.load(run_dir / "config.yaml"))
    from snakesim.envs.sb3 import SnakeVecEnv

    sb3 = PPO("MlpPolicy", SnakeVecEnv(1, **env_kwargs), policy_kwargs=policy_kwargs(arch, log_std_init=-0.7))
    state = sb3.policy.state_dict()
    assert {k: list(v.shape) for k, v in state.items() if not k.startswith(("pi_", "vf_"))} == {
        k: list(np.shape(v)) for k, v in tensors.items()
    }
    np.testing.assert_array_equal(state["log_std"].numpy(), np.full(3, -0.7, np.float32))
    out = tmp_path / "exported.zip"
    code, stdout, _ = run_cli(capsys, "export", run_dir, "--sb3", out)
    assert code == 0 and "PPO-shared [24], pi [32, 16], vf [8]" in stdout
    obs = _observations(agent.env_kwargs)
    theirs, _ = PPO.load(out, device="cpu").predict(obs, deterministic=True)
    _assert_same_actions(agent.act(obs, deterministic=True), theirs)


def _with_metadata(model: bytes, **changes: str) -> bytes:
    """A safetensors file with some of its header's metadata replaced."""
    size = int.from_bytes(model[:8], "little")
    header = json.loads(model[8 : 8 + size])
    header["__metadata__"].update(changes)
    text = json.dumps(header).encode()
    return len(text).to_bytes(8, "little") + text + model[8 + size :]


@pytest.mark.parametrize(
    ("arch", "message"),
    [
        ('{"pi": []}', "arch.pi: must have 1 to 8 layers, got 0"),
        ('{"pi": [64, 64], "heads": [1]}', "unknown field `heads`"),
        ('{"pi": [32]}', "mlp_extractor.policy_net.0.weight"),
        ("huge", "unknown arch 'huge'"),
    ],
)
def test_a_model_files_network_is_checked(tmp_path, arch, message):
    # The widths in a model file's metadata are checked as a configuration's are, and must fit its tensors.
    shipped = (Path(__file__).resolve().parents[2] / "models" / "goal-5.safetensors").read_bytes()
    path = tmp_path / "model.safetensors"
    path.write_bytes(_with_metadata(shipped, arch=arch))
    with pytest.raises(agents.AgentError) as error:
        agents.load_agent(path)
    assert "\n" not in str(error.value) and message in str(error.value), str(error.value)
    # The paper's widths spelt out are the paper's network.
    path.write_bytes(_with_metadata(shipped, arch='{"shared": [], "pi": [64, 64], "vf": [64, 64]}'))
    assert agents.load_agent(path).arch == "small"
