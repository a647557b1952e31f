"""``snakesim export MODEL --onnx OUT.onnx``: the graph, run in ONNX Runtime, gives the loader's
deterministic actions (native models and SB3 zips, small and large networks, with and without
observation statistics, observations far beyond the normalisation's clip); the command's errors are
one line and write nothing; exporting a native model imports no torch."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import onnxruntime
import pytest
import yaml
from snakesim import agents
from snakesim.cli import app as cli
from snakesim.envs.config import observation_slice
from snakesim.envs.env import make_env
from snakesim.runs import onnx as onnx_export

REPO = Path(__file__).resolve().parents[2]
MODELS = REPO / "models"
ROWS = 1000
#: |onnx - loader| on every action, absolute (the actions lie in [-1, 1]).
TOLERANCE = 1e-5

# A tiny native run (test_native.py's TINY) of PPO-large without observation statistics: a second or two.
TINY_LARGE = {
    "trainer": "native",
    "joints": 3,
    "arch": "large",
    "normalize": False,
    "n_envs": 4,
    "timesteps": 1024,
    "eval_freq": 0,
    "checkpoint_freq": 0,
    "threads": 2,
    "ppo": {"n_steps": 128, "batch_size": 64, "n_epochs": 2},
    "env": {"max_episode_steps": 200},
}


def run_cli(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def observations(agent, rows=ROWS, seed=0):
    """Half from an episode of the agent's env under random actions, half drawn around the
    normalisation's statistics (or the rollout's spread) out to 30 standard deviations, well past the
    clip at 10 (or 5)."""
    rng = np.random.default_rng(seed)
    env = make_env(**agent.env_kwargs)
    obs, _ = env.reset(seed=seed)
    rollout = []
    while len(rollout) < rows // 2:
        rollout.append(obs)
        action = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            obs, _ = env.reset(seed=seed + len(rollout))
    rollout = np.array(rollout, dtype=np.float32)
    stats = statistics(agent)
    if stats is not None:
        centre, spread = stats
    else:
        centre, spread = rollout.mean(axis=0), rollout.std(axis=0) + 0.1
    n = rows - len(rollout)
    normal = centre + spread * rng.normal(0.0, 4.0, (n // 2, centre.size))
    wide = centre + spread * rng.uniform(-30.0, 30.0, (n - n // 2, centre.size))
    return np.concatenate([rollout, normal, wide]).astype(np.float32)


def statistics(agent):
    """(mean, standard deviation) of the agent's observation statistics, or None."""
    if agent.kind == "native":
        stats = agent.policy.obs_rms()
        return None if stats is None else (stats[0], np.sqrt(stats[1]))
    if agent.obs_normalizer is None:
        return None
    rms = agent.obs_normalizer.obs_rms
    return rms.mean, np.sqrt(rms.var)


def session(path):
    return onnxruntime.InferenceSession(str(path), providers=["CPUExecutionProvider"])


def assert_acts_as_the_loader(path, agent, seed=0, clipped=True):
    """The graph at ``path`` against the loaded agent's deterministic actions; the largest difference."""
    obs = observations(agent, seed=seed)
    ours = session(path).run([onnx_export.OUTPUT], {onnx_export.INPUT: obs})[0]
    theirs = np.asarray(agent.act(obs, deterministic=True), dtype=np.float32)
    act_dim = agent.policy.act_dim if agent.kind == "native" else agent.policy.action_space.shape[0]
    assert ours.dtype == np.float32 and ours.shape == theirs.shape == (ROWS, act_dim)
    error = float(np.abs(ours - theirs).max())
    assert error <= TOLERANCE, f"{path.name}: max |onnx - loader| = {error:.3g}"
    # The actions cover the action space, clipped: the comparison is not between two near-zero outputs.
    assert float(np.abs(theirs).max()) == 1.0 or not clipped
    print(f"{agent.path}: max |onnx - loader| over {ROWS} observations = {error:.3g}")
    return error


def export(capsys, source, out, *more):
    code, stdout, err = run_cli(capsys, "export", source, "--onnx", out, *more)
    assert code == 0, err
    assert f"wrote {out}" in stdout
    return out


# -- native models ----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "name",
    [
        "goal-10",  # gait actions, the extended observation (30), normalised
        "paper-10",  # joint targets (10 actions), the paper's observation (22), normalised
        "rough-10",  # gait actions, the terrain observation with its height map (58), normalised
    ],
)
def test_shipped_native_models_act_alike(name, tmp_path, capsys):
    model = MODELS / f"{name}.safetensors"
    if name == "rough-10":
        # Its steer_assist (baseline:steer drives near the goal) is not in a graph of the policy, so
        # the export is refused; the policy itself is checked on a copy without the assist.
        code, _, err = run_cli(capsys, "export", model, "--onnx", tmp_path / "refused.onnx")
        assert code != 0 and "trained with steer_assist" in err and err.count("\n") == 1
        assert not (tmp_path / "refused.onnx").exists()
        from safetensors import safe_open
        from safetensors.numpy import load_file, save_file

        with safe_open(str(model), "np") as f:
            meta = {k: v for k, v in f.metadata().items() if k != "steer_assist"}
        model = tmp_path / "rough-10-policy.safetensors"
        save_file(load_file(str(MODELS / "rough-10.safetensors")), str(model), metadata=meta)
    out = export(capsys, model, tmp_path / f"{name}.onnx")
    agent = agents.load_agent(model)
    assert agent.kind == "native" and agent.policy.normalize
    assert_acts_as_the_loader(out, agent)


@pytest.fixture(scope="module")
def large_run(tmp_path_factory):
    base = tmp_path_factory.mktemp("native-large")
    config = base / "config.yaml"
    config.write_text(yaml.safe_dump(TINY_LARGE))
    run = base / "run"
    argv = ["train", "--config", str(config), "--run-dir", str(run), "--no-progress"]
    assert cli.main(argv) == 0
    return run


def with_larger_actions(model: Path, out: Path, factor: float = 60.0) -> Path:
    """A copy of a native model with ``action_net.weight`` times ``factor``: a freshly initialised
    policy's actions are small (SB3's output gain is 0.01), a trained one's reach the clip."""
    raw = bytearray(model.read_bytes())
    size = int.from_bytes(raw[:8], "little")
    begin, end = json.loads(raw[8 : 8 + size])["action_net.weight"]["data_offsets"]
    start = 8 + size
    weight = np.frombuffer(bytes(raw[start + begin : start + end]), dtype="<f4") * np.float32(factor)
    raw[start + begin : start + end] = weight.astype("<f4").tobytes()
    out.write_bytes(bytes(raw))
    return out


def test_a_native_large_run_without_statistics_acts_alike(large_run, tmp_path, capsys):
    agent = agents.load_agent(large_run)
    assert agent.arch == "large" and agent.policy.obs_rms() is None
    out = export(capsys, large_run, tmp_path / "large.onnx")
    assert_acts_as_the_loader(out, agent, clipped=False)
    model = with_larger_actions(large_run / "model.safetensors", tmp_path / "large.safetensors")
    out = export(capsys, model, tmp_path / "larger.onnx")
    assert_acts_as_the_loader(out, agents.load_agent(model))


def test_the_graph_s_interface_and_metadata(tmp_path, capsys):
    out = export(capsys, MODELS / "paper-10.safetensors", tmp_path / "paper-10.onnx")
    graph = session(out)
    (given,) = graph.get_inputs()
    (taken,) = graph.get_outputs()
    assert (given.name, given.type, given.shape) == ("observation", "tensor(float)", ["batch", 22])
    assert (taken.name, taken.type, taken.shape) == ("action", "tensor(float)", ["batch", 10])
    meta = graph.get_modelmeta().custom_metadata_map
    env = make_env(joints=10, preset="snakebot-gym")
    assert json.loads(meta["snakesim.observation_structure"]) == env.observation_structure
    # The joints mode passes its actions through no wave: the file lists no gait ranges.
    assert json.loads(meta["snakesim.action"]) == {"mode": "joints"}
    assert json.loads(meta["snakesim.action_scale"]) == 1.0
    assert json.loads(meta["snakesim.normalization"]) == {"epsilon": 1e-8, "clip": 10.0}
    # A batch of one, and an empty batch: the batch is dynamic.
    agent = agents.load_agent(MODELS / "paper-10.safetensors")
    obs = observations(agent, rows=2)[:1]
    (one,) = graph.run(None, {"observation": obs})
    np.testing.assert_allclose(one, agent.act(obs), atol=TOLERANCE, rtol=0)
    assert graph.run(None, {"observation": np.zeros((0, 22), np.float32)})[0].shape == (0, 10)


def test_a_gait_mode_model_lists_the_ranges_its_wave_reads(tmp_path, capsys):
    out = export(capsys, MODELS / "goal-10.safetensors", tmp_path / "goal-10.onnx")
    meta = session(out).get_modelmeta().custom_metadata_map
    # The env's own action table (snake-core's ActionConfig defaults for the goal task).
    action = make_env(task="goal", joints=10).config["action"]
    assert action["mode"] == "gait"
    assert json.loads(meta["snakesim.action"]) == {
        "mode": "gait",
        "steering": action["steering"],
        "amplitude": action["amplitude"],
        "frequency": action["frequency"],
    }


def test_exporting_a_native_model_imports_no_torch(tmp_path):
    # The light install (no torch) exports: the library's path, in a fresh interpreter.
    out = tmp_path / "goal-10.onnx"
    probe = (
        "import sys\n"
        "from snakesim.agents import load_agent\n"
        "from snakesim.runs.onnx import to_onnx\n"
        f"to_onnx(load_agent({str(MODELS / 'goal-10.safetensors')!r}), {str(out)!r})\n"
        "print(sorted(m for m in ('torch', 'stable_baselines3') if m in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]" and out.stat().st_size > 1000


class SimulatedRobot:
    """The hardware interface docs/deploy.md's control loop assumes, over the env it was trained in."""

    def __init__(self, env, steps):
        self.env, self.steps = env, steps
        self.obs, _ = env.reset(seed=3)
        self.seen, self.sent = [], []
        self.stopped = False

    def stop(self):
        self.stopped = True

    def part(self, name):
        return self.obs[observation_slice(self.env.observation_structure, name)]

    def running(self):
        return len(self.sent) < self.steps

    def read_joints(self):
        states = self.part("joint_states")
        return states[0::2], states[1::2]

    def head_xy(self):
        return self.part("base_position")

    def set_joint_targets(self, targets):
        self.seen.append(self.obs)
        self.sent.append(np.asarray(targets, dtype=np.float32))
        self.obs, *_ = self.env.step(self.sent[-1] / self.env.config["action_scale"])


def control_loop(out):
    """docs/deploy.md's control loop, reading ``out``."""
    page = (REPO / "docs" / "deploy.md").read_text()
    loop = page.split("## A control loop", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    assert '"out/paper-10.onnx"' in loop, "the loop reads the file the page's export writes"
    return compile(loop.replace('"out/paper-10.onnx"', repr(str(out))), "deploy.md", "exec")


def test_the_control_loop_of_docs_deploy_md_runs(tmp_path, capsys, monkeypatch):
    model = MODELS / "paper-10.safetensors"
    out = export(capsys, model, tmp_path / "paper-10.onnx")
    agent = agents.load_agent(model)
    robot = SimulatedRobot(make_env(**agent.env_kwargs), steps=20)
    monkeypatch.setattr("time.sleep", lambda seconds: None)
    exec(control_loop(out), {"robot": robot})
    assert len(robot.sent) == 20 and not robot.stopped
    expected = np.clip(agent.act(np.array(robot.seen)), -1, 1) * robot.env.config["action_scale"]
    np.testing.assert_allclose(np.array(robot.sent), expected, atol=TOLERANCE, rtol=0)


class FailingSensor(SimulatedRobot):
    """A robot whose joint encoder ``joint`` reads ``value`` from step ``at`` on."""

    def __init__(self, env, steps, at, joint, value):
        super().__init__(env, steps)
        self.at, self.joint, self.value = at, joint, value

    def read_joints(self):
        angles, velocities = (np.array(part) for part in super().read_joints())
        if len(self.sent) >= self.at:
            angles[self.joint] = self.value
        return angles, velocities


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_the_graph_acts_on_what_act_refuses_and_the_loop_stops(value, tmp_path, capsys, monkeypatch):
    """The issue's case: a NaN observation gives NaN actions from the graph (an infinite one, actions
    from its clip), where act refuses it; the documented loop stops the robot instead of acting."""
    model = MODELS / "paper-10.safetensors"
    out = export(capsys, model, tmp_path / "paper-10.onnx")
    agent = agents.load_agent(model)
    obs = observations(agent, rows=4)
    obs[1, 3] = value  # joint 0's velocity (after the head's x and y and joint 0's angle)
    graph = session(out).run([onnx_export.OUTPUT], {onnx_export.INPUT: obs})[0]
    if np.isnan(value):
        assert np.isnan(graph[1]).all() and np.isfinite(graph[[0, 2, 3]]).all()
    else:
        assert np.isfinite(graph).all()  # clipped by the normalisation: it would act
    with pytest.raises(ValueError, match=r"obs\[1, 3\] must be finite"):
        agent.act(obs)
    robot = FailingSensor(make_env(**agent.env_kwargs), steps=20, at=7, joint=1, value=value)
    monkeypatch.setattr("time.sleep", lambda seconds: None)
    with pytest.raises(RuntimeError, match=r"observation \[4\] not finite"):
        exec(control_loop(out), {"robot": robot})
    assert robot.stopped and len(robot.sent) == 7 and np.isfinite(np.array(robot.sent)).all()


# -- SB3 models -------------------------------------------------------------------------------------
def test_an_exported_sb3_zip_with_statistics_acts_alike(tmp_path, capsys):
    # The native goal-10 as SB3 (zip + NAME_vecnormalize.pkl), then that zip as ONNX: one command each,
    # and both flags at once give the same graph.
    zipped = tmp_path / "goal-10.zip"
    code, stdout, err = run_cli(
        capsys, "export", MODELS / "goal-10.safetensors", "--sb3", zipped, "--onnx", tmp_path / "both.onnx"
    )
    assert code == 0 and len(stdout.strip().splitlines()) == 2, err
    assert (tmp_path / "goal-10_vecnormalize.pkl").is_file() and (tmp_path / "both.onnx").is_file()
    out = export(capsys, zipped, tmp_path / "from-zip.onnx")
    agent = agents.load_agent(zipped)
    assert agent.kind == "sb3" and agent.obs_normalizer is not None
    assert_acts_as_the_loader(out, agent)
    assert_acts_as_the_loader(tmp_path / "both.onnx", agents.load_agent(MODELS / "goal-10.safetensors"))


@pytest.mark.parametrize(
    ("activation", "arch"),
    [
        ("Tanh", "large"),  # the paper's PPO-large: a shared trunk of 128, 128, then heads
        ("Tanh", "small"),
        ("ReLU", {"shared": [24], "pi": [32, 16], "vf": [8]}),
        ("LeakyReLU", "small"),
        ("ELU", "large"),
        ("GELU", {"pi": [48], "vf": [16, 16]}),
        ("SiLU", "small"),
        ("Sigmoid", "small"),
    ],
)
def test_sb3_zips_of_every_network_act_alike(activation, arch, tmp_path, capsys):
    """A bare SB3 zip with its statistics beside it (an epsilon and a clip of their own), weights
    drawn large enough that the actions reach the clip."""
    import torch
    from snakesim.envs.sb3 import SnakeVecEnv
    from snakesim.runs.policies import policy_kwargs
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    joints = 4
    kwargs = policy_kwargs(arch)
    kwargs["activation_fn"] = getattr(torch.nn, activation)
    venv = SnakeVecEnv(1, joints=joints)
    model = PPO("MlpPolicy", venv, policy_kwargs=kwargs, device="cpu", seed=0)
    generator = torch.Generator().manual_seed(1)
    with torch.no_grad():
        for module in model.policy.modules():
            if isinstance(module, torch.nn.Linear):
                std = 1.5 / np.sqrt(module.in_features)
                module.weight.copy_(torch.randn(module.weight.shape, generator=generator) * std)
                module.bias.copy_(torch.randn(module.bias.shape, generator=generator) * 0.3)
    zipped = tmp_path / "model.zip"
    model.save(zipped)
    rng = np.random.default_rng(2)
    normalizer = VecNormalize(venv, norm_obs=True, norm_reward=False, clip_obs=5.0, epsilon=1e-4)
    dim = venv.observation_space.shape[0]
    normalizer.obs_rms.mean = rng.normal(0.0, 1.0, dim)
    normalizer.obs_rms.var = rng.uniform(0.0, 2.0, dim) ** 2
    normalizer.obs_rms.var[0] = 0.0  # a constant observation: epsilon alone scales it
    normalizer.save(str(tmp_path / "model_vecnormalize.pkl"))
    out = export(capsys, zipped, tmp_path / "model.onnx")
    agent = agents.load_agent(zipped)
    assert agent.obs_normalizer is not None and agent.obs_normalizer.clip_obs == 5.0
    meta = session(out).get_modelmeta().custom_metadata_map
    assert json.loads(meta["snakesim.normalization"]) == {"epsilon": 1e-4, "clip": 5.0}
    assert_acts_as_the_loader(out, agent)


def test_an_sb3_zip_without_statistics_acts_alike(tmp_path, capsys):
    import torch
    from snakesim.envs.sb3 import SnakeVecEnv
    from snakesim.runs.policies import policy_kwargs
    from stable_baselines3 import PPO

    model = PPO("MlpPolicy", SnakeVecEnv(1, joints=5), policy_kwargs=policy_kwargs("large"), device="cpu")
    with torch.no_grad():
        model.policy.action_net.weight.mul_(100.0)  # SB3 initialises it small (gain 0.01)
    model.save(tmp_path / "bare.zip")
    out = export(capsys, tmp_path / "bare.zip", tmp_path / "bare.onnx")
    agent = agents.load_agent(tmp_path / "bare.zip")
    assert agent.obs_normalizer is None
    assert json.loads(session(out).get_modelmeta().custom_metadata_map["snakesim.normalization"]) is None
    assert_acts_as_the_loader(out, agent)


# -- the command's errors ---------------------------------------------------------------------------
@pytest.fixture
def model_copy(tmp_path):
    """goal-10, copied into the folder the outputs would go to; named .onnx, as an output could be."""
    copy = tmp_path / "model.onnx"
    copy.write_bytes((MODELS / "goal-10.safetensors").read_bytes())
    (tmp_path / "folder.onnx").mkdir()
    return copy


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["{model}"], "give --onnx POLICY.onnx, --sb3 MODEL.zip or both"),
        (
            ["{model}", "--onnx", "{tmp}/policy.txt"],
            "cannot write --onnx {tmp}/policy.txt: expected a .onnx file",
        ),
        (["{model}", "--onnx", "{tmp}/policy"], "expected a .onnx file"),
        (["{model}", "--onnx", "{tmp}/missing/policy.onnx"], "directory {tmp}/missing does not exist"),
        (
            ["{model}", "--onnx", "{tmp}/folder.onnx"],
            "cannot write --onnx {tmp}/folder.onnx: it is a directory",
        ),
        (["{model}", "--onnx", "{model}"], "it is {model}, which this command reads"),
        (["{model}", "--onnx", "{tmp}/p.onnx", "--sb3", "{tmp}/p.txt"], "--sb3 {tmp}/p.txt: expected a .zip"),
        (
            ["baseline:steer", "--onnx", "{tmp}/p.onnx"],
            "baseline:steer is a hand-made controller, not a model",
        ),
        (["{tmp}/absent.safetensors", "--onnx", "{tmp}/p.onnx"], "absent.safetensors does not exist"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(argv, message, model_copy, tmp_path, capsys):
    before = {p: p.stat().st_mtime_ns for p in tmp_path.rglob("*")}
    content = model_copy.read_bytes()
    argv = [a.format(model=model_copy, tmp=tmp_path) for a in argv]
    code, out, err = run_cli(capsys, "export", *argv)
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and lines[0].startswith("snakesim export: error: "), err
    assert message.format(model=model_copy, tmp=tmp_path) in lines[0], lines[0]
    assert out == ""
    assert {p: p.stat().st_mtime_ns for p in tmp_path.rglob("*")} == before, "nothing is written"
    assert model_copy.read_bytes() == content


def test_an_unwritable_folder_is_one_line(tmp_path, capsys):
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        if os.access(folder, os.W_OK):
            pytest.skip("this user (root) may write into a read-only folder")
        code, _, err = run_cli(capsys, "export", MODELS / "goal-10.safetensors", "--onnx", folder / "p.onnx")
        assert (
            code == 1 and f"directory {folder} is not writable" in err and len(err.strip().splitlines()) == 1
        )
        assert not list(folder.iterdir())
    finally:
        folder.chmod(0o700)


def test_an_sb3_zip_refuses_sb3_but_exports_onnx(tmp_path, capsys):
    zipped = tmp_path / "goal-10.zip"
    assert run_cli(capsys, "export", MODELS / "goal-10.safetensors", "--sb3", zipped)[0] == 0
    before = sorted(tmp_path.iterdir())
    code, _, err = run_cli(
        capsys, "export", zipped, "--sb3", tmp_path / "again.zip", "--onnx", tmp_path / "p.onnx"
    )
    assert code == 1 and "is already a Stable-Baselines3 model" in err and len(err.strip().splitlines()) == 1
    assert sorted(tmp_path.iterdir()) == before, "neither output is written"
    assert run_cli(capsys, "export", zipped, "--onnx", tmp_path / "p.onnx")[0] == 0


def test_the_library_refuses_baselines():
    with pytest.raises(onnx_export.ExportError, match="hand-made controller"):
        onnx_export.to_onnx_bytes(agents.load_agent("baseline:steer"))
