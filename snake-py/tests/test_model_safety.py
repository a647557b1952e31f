"""Hardening, round 4 (issue 45), the Python side: loading a model never runs code from it, exported zips
evaluate as the native model, reads are bounded, outputs never replace devices, FIFOs, links or inputs,
SIGTERM unwinds, and every error is one line."""

from __future__ import annotations

import base64
import copyreg
import io
import json
import os
import pickle
import re
import signal
import stat
import subprocess
import sys
import threading
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
from snakesim import agents
from snakesim.agents.loading import load_normalizer
from snakesim.cli import app as cli
from snakesim.limits import LIMITS

REPO = Path(__file__).resolve().parents[2]
MODELS = REPO / "models"


class Payload:
    """Unpickled, it runs code: it creates the marker file."""

    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self):
        return (exec, (f"open({self.marker!r}, 'w').close()",))


def serialized(marker: Path) -> dict:
    """A `data` entry as SB3 writes a pickled one, carrying the payload."""
    blob = base64.b64encode(pickle.dumps(Payload(marker))).decode()
    return {":type:": "<class 'function'>", ":serialized:": blob}


def rewrite_zip(path: Path, out: Path, **members: bytes) -> Path:
    with zipfile.ZipFile(path) as archive:
        content = {name: archive.read(name) for name in archive.namelist()}
    content.update(members)
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in content.items():
            archive.writestr(name, data)
    return out


def poisoned(path: Path, out: Path, key: str, marker: Path, **changes) -> Path:
    """A copy of the zip whose `data[key]` (a new key, or one SB3 pickles) carries the payload."""
    with zipfile.ZipFile(path) as archive:
        data = json.loads(archive.read("data"))
    data[key] = serialized(marker)
    data.update(changes)
    return rewrite_zip(path, out, data=json.dumps(data).encode())


def run_cli(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def one_line_error(capsys, *argv) -> str:
    code, _, err = run_cli(capsys, *argv)
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and "error:" in lines[0], err
    return lines[0]


def test_the_payload_runs_when_unpickled(tmp_path):
    # What the tests below guard against is real: plain unpickling (SB3's PPO.load, pickle.load) runs it.
    marker = tmp_path / "ran"
    pickle.loads(base64.b64decode(serialized(marker)[":serialized:"]))
    assert marker.exists()


# -- models to load -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """models/goal-5.safetensors (which normalises observations) exported: goal-5.zip and its statistics."""
    out = tmp_path_factory.mktemp("exported") / "goal-5.zip"
    assert cli.main(["export", str(MODELS / "goal-5.safetensors"), "--sb3", str(out)]) == 0
    assert (out.parent / "goal-5_vecnormalize.pkl").is_file()
    return out


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """Zips that Stable-Baselines3 itself trained and saved: its default MlpPolicy, and snakesim's large
    network (a shared trunk as a features extractor)."""
    from snakesim.envs.sb3 import SnakeVecEnv
    from snakesim.runs.policies import policy_kwargs
    from stable_baselines3 import PPO

    folder = tmp_path_factory.mktemp("trained")
    paths = {}
    for name, kwargs in (("default", None), ("large", policy_kwargs("large"))):
        model = PPO(
            "MlpPolicy",
            SnakeVecEnv(2, joints=3),
            n_steps=128,
            batch_size=64,
            n_epochs=1,
            policy_kwargs=kwargs,
            device="cpu",
            seed=0,
        )
        model.learn(256)
        paths[name] = folder / f"{name}.zip"
        model.save(paths[name])
    return paths


def observations(env_kwargs: dict, count: int = 200) -> np.ndarray:
    """Observations of an episode (random actions) in the env of ``env_kwargs``."""
    from snakesim.envs.env import make_env

    env = make_env(**env_kwargs)
    obs, _ = env.reset(seed=3)
    rng = np.random.default_rng(0)
    out = []
    for _ in range(count):
        out.append(obs)
        action = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            obs, _ = env.reset()
    return np.array(out, dtype=np.float32)


# -- 1. no code runs on load ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "key", ["extra", "lr_schedule", "clip_range", "policy_class", "policy_kwargs", "observation_space"]
)
@pytest.mark.parametrize("model", ["default", "large"])
def test_no_pickled_entry_of_a_zip_runs(trained, tmp_path, key, model):
    marker = tmp_path / "ran"
    path = poisoned(trained[model], tmp_path / "model.zip", key, marker)
    try:
        agent = agents.load_agent(path)
    except agents.AgentError as error:
        # Only the spaces are needed from a pickled entry, and their shapes are gone with it.
        assert key == "observation_space" and "has no Box observation/action spaces" in str(error)
    else:
        assert agent.kind == "sb3" and np.isfinite(agent.act(np.zeros((1, 8), np.float32))).all()
        assert agents.inspect_model(path).action_dim == 3
    assert not marker.exists()


def test_no_pickled_entry_of_an_sb3_1x_zip_runs(trained, tmp_path):
    # The same zip as SB3 1.x labels it (gym spaces): the paper's format, read through its own path.
    marker = tmp_path / "ran"
    with zipfile.ZipFile(trained["default"]) as archive:
        data = json.loads(archive.read("data"))
    for space in ("observation_space", "action_space"):
        data[space] = {
            **data[space],
            ":type:": "<class 'gym.spaces.box.Box'>",
            "shape": data[space]["_shape"],
        }
    data["lr_schedule"] = serialized(marker)
    path = rewrite_zip(
        trained["default"],
        tmp_path / "legacy.zip",
        data=json.dumps(data).encode(),
        _stable_baselines3_version=b"1.8.0",
    )
    agent = agents.load_agent(path)
    assert agent.sb3_version == "1.8.0" and agent.arch == "small"
    assert not marker.exists()


@pytest.fixture
def poisoned_copies(exported, tmp_path):
    """The exported zip twice: with a payload in its data (statistics intact), and intact with a
    payload as its statistics."""
    marker = tmp_path / "ran"
    in_data = poisoned(exported, tmp_path / "data.zip", "extra", marker)
    (tmp_path / "data_vecnormalize.pkl").write_bytes(
        (exported.parent / "goal-5_vecnormalize.pkl").read_bytes()
    )
    in_stats = tmp_path / "stats.zip"
    in_stats.write_bytes(exported.read_bytes())
    (tmp_path / "stats_vecnormalize.pkl").write_bytes(pickle.dumps(Payload(marker)))
    return marker, in_data, in_stats


@pytest.mark.parametrize(
    ("command", "code"),
    [
        (["evaluate", "{zip}", "--episodes", 1], 0),
        (["replay", "{zip}", "--seconds", 0.1, "--out", "{tmp}/r.png"], 0),
        (["export", "{zip}", "--sb3", "{tmp}/again.zip"], 1),  # refused: already SB3, but loaded first
        (["evaluate", "baseline:steer", "--env-from", "{zip}", "--episodes", 1], 0),
    ],
)
def test_no_command_runs_code_from_a_model(poisoned_copies, tmp_path, capsys, command, code):
    marker, in_data, in_stats = poisoned_copies
    argv = [str(a).format(zip=in_data, tmp=tmp_path) for a in command]
    got, _, err = run_cli(capsys, *argv)
    assert got == code, err
    argv = [str(a).format(zip=in_stats, tmp=tmp_path) for a in command]
    line = one_line_error(capsys, *argv)
    assert f"{tmp_path / 'stats_vecnormalize.pkl'}: refused: the pickle names builtins.exec" in line, line
    assert "which a VecNormalize file does not hold" in line
    assert not marker.exists()


def test_the_python_api_runs_no_code_either(poisoned_copies):
    marker, in_data, in_stats = poisoned_copies
    assert agents.load_agent(in_data).obs_normalizer is not None
    with pytest.raises(agents.AgentError, match="refused: the pickle names builtins.exec"):
        agents.load_agent(in_stats)
    with pytest.raises(agents.AgentError, match="refused"):
        agents.load_agent("baseline:gait", env_from=in_stats)
    assert not marker.exists()


def test_a_payload_inside_real_statistics_is_refused(tmp_path):
    from snakesim.envs.sb3 import SnakeVecEnv
    from stable_baselines3.common.vec_env import VecNormalize

    normalizer = VecNormalize(SnakeVecEnv(1, joints=3), training=False)
    normalizer.clip_obs = Payload(tmp_path / "ran")  # anywhere in the object, not only at its top
    path = tmp_path / "stats.pkl"
    path.write_bytes(pickle.dumps(normalizer))
    with pytest.raises(agents.AgentError, match="refused: the pickle names builtins.exec"):
        load_normalizer(path)
    assert not (tmp_path / "ran").exists()


# -- the models that must still load ------------------------------------------------------------------
@pytest.mark.parametrize("path", sorted(MODELS.glob("*.safetensors")), ids=lambda p: p.name)
def test_every_shipped_model_loads(path):
    agent = agents.load_agent(path)
    assert agent.kind == "native" and agent.files == (str(path),)
    assert np.isfinite(agent.act(np.zeros((1, agent.policy.obs_dim), np.float32))).all()


def test_zips_act_as_sb3_loads_them(trained, exported):
    """Rebuilt from the weights' shapes, without unpickling: the same network as PPO.load builds, so
    bit for bit the same actions (normalised by the same statistics where there are some)."""
    from snakesim.envs.sb3 import SnakeVecEnv
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    for path, arch in ((trained["default"], "small"), (trained["large"], "large"), (exported, "small")):
        agent = agents.load_agent(path)
        assert agent.arch == arch
        obs = observations(agent.env_kwargs)
        sb3_obs = obs
        if agent.obs_normalizer is not None:
            stats = path.with_name(f"{path.stem}_vecnormalize.pkl")
            sb3_obs = VecNormalize.load(str(stats), SnakeVecEnv(1, **agent.env_kwargs)).normalize_obs(obs)
        theirs, _ = PPO.load(path, device="cpu").predict(sb3_obs, deterministic=True)
        np.testing.assert_array_equal(agent.act(obs, deterministic=True), theirs)


def test_weights_that_do_not_fit_are_one_line(trained, tmp_path):
    import torch

    with zipfile.ZipFile(trained["large"]) as archive:
        state = torch.load(io.BytesIO(archive.read("policy.pth")), weights_only=True)
    # A trunk whose pi/vf copies differ (separate extractors), and a layer that does not take its input.
    split = dict(state)
    split["vf_features_extractor.shared_net.0.bias"] = split["vf_features_extractor.shared_net.0.bias"] + 1
    skewed = dict(state)
    skewed["mlp_extractor.policy_net.2.weight"] = torch.zeros(64, 7)
    for weights, message in ((split, "separate policy and value trunks"), (skewed, "do not fit the network")):
        buffer = io.BytesIO()
        torch.save(weights, buffer)
        path = rewrite_zip(trained["large"], tmp_path / "bad.zip", **{"policy.pth": buffer.getvalue()})
        with pytest.raises(agents.AgentError) as error:
            agents.load_agent(path)
        assert message in str(error.value) and "\n" not in str(error.value)


# -- 2. an export evaluates as the model it came from --------------------------------------------------
def test_an_exported_model_evaluates_as_the_native_one(tmp_path, capsys):
    """The issue's case: models/paper-10.safetensors normalises observations; its export, evaluated on
    its own, once scored 0.20 where the native model scores 1.00 (the statistics beside it were ignored)."""
    native_path = MODELS / "paper-10.safetensors"
    out = tmp_path / "p.zip"
    assert run_cli(capsys, "export", native_path, "--sb3", out)[0] == 0
    native = agents.load_agent(native_path)
    exported_agent = agents.load_agent(out, joints=10, preset="snakebot-gym")
    assert exported_agent.files == (str(out), str(tmp_path / "p_vecnormalize.pkl"))
    assert exported_agent.env_kwargs == native.env_kwargs
    # The same actions up to float32 rounding: torch and the native network sum in different orders,
    # so the last bit differs (the tolerance of test_native's export tests).
    obs = observations(native.env_kwargs)
    ours, theirs = native.act(obs), exported_agent.act(obs)
    assert float(np.abs(ours - theirs).max()) <= 1e-5 * float(np.abs(ours).max())
    # Episodes: those last bits grow in a chaotic contact simulation (after ~100 steps the paths part
    # by millimetres), so returns are compared over short episodes, where they agree to float32
    # rounding; the success of whole episodes is compared exactly.
    short = {"max_episode_steps": 20}
    a = agents.evaluate(agents.load_agent(native_path, env_overrides=short), 3, seed=3)
    b = agents.evaluate(
        agents.load_agent(out, joints=10, preset="snakebot-gym", env_overrides=short), 3, seed=3
    )
    assert [e["steps"] for e in a["per_episode"]] == [e["steps"] for e in b["per_episode"]]
    np.testing.assert_allclose(
        [e["return"] for e in b["per_episode"]], [e["return"] for e in a["per_episode"]], rtol=1e-6
    )
    reports = []
    # The command for the zip (the export also records its env: the flags only agree with it).
    for argv in ([native_path], [out, "--joints", 10, "--preset", "snakebot-gym"]):
        code, stdout, err = run_cli(capsys, "evaluate", *argv, "--episodes", 2, "--seed", 3, "--json", "-")
        assert code == 0, err
        reports.append(json.loads(stdout))
    assert reports[1]["success_rate"] == reports[0]["success_rate"] == 1.0
    assert [e["success"] for e in reports[1]["per_episode"]] == [
        e["success"] for e in reports[0]["per_episode"]
    ]


# -- 4. bounded reads ---------------------------------------------------------------------------------
def snakesim(*argv, timeout=60, **kwargs):
    return subprocess.run(
        [sys.executable, "-m", "snakesim", *map(str, argv)],
        capture_output=True,
        text=True,
        timeout=timeout,
        **kwargs,
    )


def test_devices_and_fifos_are_refused_at_once(tmp_path):
    fifo = tmp_path / "model.zip"
    os.mkfifo(fifo)
    for path in ("/dev/zero", fifo):
        started = time.monotonic()
        done = snakesim("evaluate", path)  # in a child: a hang fails by its timeout
        assert done.returncode == 1 and time.monotonic() - started < 30
        assert (
            done.stderr
            == f"snakesim evaluate: error: {path}: not a regular file (a device, FIFO or socket)\n"
        )


def _zip_with(path: Path, name: str, size: int) -> Path:
    """A model zip whose member `name` inflates to `size` zero bytes (a few hundred KiB on disk)."""
    spaces = {"observation_space": {"_shape": [8]}, "action_space": {"_shape": [3]}}
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for other, content in (("data", json.dumps(spaces).encode()), ("policy.pth", b"")):
            if other != name:
                archive.writestr(other, content)
        with archive.open(name, "w", force_zip64=True) as member:
            chunk = bytes(1 << 20)
            for _ in range(size >> 20):
                member.write(chunk)
    return path


def test_sizes_are_capped(tmp_path, capsys):
    bomb = _zip_with(tmp_path / "bomb.zip", "policy.pth", LIMITS["model_bytes"] + (1 << 20))
    line = one_line_error(capsys, "evaluate", bomb)
    assert (
        f"{bomb}: member policy.pth is 257 MiB, more than the 256 MiB allowed (LIMITS['model_bytes'])" in line
    )
    data = _zip_with(tmp_path / "data.zip", "data", LIMITS["config_bytes"] + (1 << 20))
    assert "member data is 17 MiB, more than the 16 MiB allowed (LIMITS['config_bytes'])" in one_line_error(
        capsys, "evaluate", data
    )
    huge = tmp_path / "huge.zip"
    with open(huge, "wb") as f:  # sparse: no disk used
        f.write(b"PK\x03\x04")
        f.truncate(LIMITS["model_bytes"] + 1)
    assert "(LIMITS['model_bytes'])" in one_line_error(capsys, "evaluate", huge)
    run = tmp_path / "run"
    run.mkdir()
    with open(run / "config.yaml", "wb") as f:
        f.truncate(LIMITS["config_bytes"] + 1)
    line = one_line_error(capsys, "evaluate", run)
    assert "config.yaml is 16,777,217 bytes, more than the 16 MiB allowed (LIMITS['config_bytes'])" in line


def test_statistics_are_capped_and_checked(exported, tmp_path, capsys):
    model = tmp_path / "m.zip"
    model.write_bytes(exported.read_bytes())
    stats = tmp_path / "m_vecnormalize.pkl"
    with open(stats, "wb") as f:
        f.truncate(LIMITS["config_bytes"] + 1)
    assert "(LIMITS['config_bytes'])" in one_line_error(capsys, "evaluate", model)
    # Statistics of another model (3 joints: 8 observations; goal-5 takes 20).
    from snakesim.envs.sb3 import SnakeVecEnv
    from stable_baselines3.common.vec_env import VecNormalize

    VecNormalize(SnakeVecEnv(1, joints=3), training=False).save(str(stats))
    assert "not the statistics of 20 finite observations" in one_line_error(capsys, "evaluate", model)


@pytest.mark.parametrize(
    ("row", "column"), [("inf,1,1,1,1,1", "timesteps"), ("1,nan,1,1,1,1", "mean_return")]
)
def test_a_plot_of_non_finite_evaluations_is_one_line(tmp_path, capsys, row, column):
    csv_path = tmp_path / "evaluations.csv"
    csv_path.write_text(
        "timesteps,mean_return,std_return,success_rate,mean_steps_to_goal,wall_time\n0,1,1,1,nan,1\n"
        + row
        + "\n"
    )
    line = one_line_error(capsys, "plot", csv_path, "--out", tmp_path / "f.png")
    assert f"{csv_path}: line 3, column {column}: " in line and "is not a finite number" in line
    assert not (tmp_path / "f.png").exists()


# -- 3. outputs -------------------------------------------------------------------------------------
EVALUATE = ["evaluate", MODELS / "goal-5.safetensors", "--episodes", 1]


def test_json_into_a_device_a_fifo_and_through_a_link(tmp_path, capsys):
    assert run_cli(capsys, *EVALUATE, "--json", "/dev/null")[0] == 0
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode), "/dev/null is still the device"
    fifo = tmp_path / "out.json"
    os.mkfifo(fifo)
    done = snakesim(*EVALUATE, "--json", fifo)  # nobody reads: refused, not waited on
    assert done.returncode == 1 and done.stderr.strip().endswith(
        f"cannot write {fifo}: a FIFO that nobody reads"
    )
    read: list[bytes] = []
    reader = threading.Thread(target=lambda: read.append(fifo.read_bytes()))
    reader.start()
    time.sleep(0.2)  # the reader opens the FIFO first
    assert run_cli(capsys, *EVALUATE, "--json", fifo)[0] == 0
    reader.join(timeout=30)
    assert json.loads(read[0])["episodes"] == 1 and stat.S_ISFIFO(os.stat(fifo).st_mode)
    target, link = tmp_path / "real.json", tmp_path / "link.json"
    target.write_text("old")
    link.symlink_to(target)
    assert run_cli(capsys, *EVALUATE, "--json", link)[0] == 0
    assert link.is_symlink() and json.loads(target.read_text())["episodes"] == 1


def test_an_output_onto_an_input_is_refused(exported, tmp_path, capsys):
    model = tmp_path / "goal-5.safetensors"
    model.write_bytes((MODELS / "goal-5.safetensors").read_bytes())
    before = model.read_bytes()
    line = one_line_error(capsys, "evaluate", model, "--episodes", 1, "--json", model)
    assert f"cannot write --json {model}: it is {model}, which this command reads" in line
    disguised = tmp_path / "native.zip"  # a native model by its content, named as a zip
    disguised.write_bytes(before)
    assert "which this command reads" in one_line_error(capsys, "export", disguised, "--sb3", disguised)
    stats = exported.parent / "goal-5_vecnormalize.pkl"
    assert "which this command reads" in one_line_error(capsys, "evaluate", exported, "--json", stats)
    link = tmp_path / "link.png"
    link.symlink_to(tmp_path / "r.png")
    line = one_line_error(capsys, "replay", model, "--out", tmp_path / "r.png", "--out", link)
    assert "name the same file" in line
    assert model.read_bytes() == before and disguised.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["goal-5.safetensors", "link.png", "native.zip"]


def test_an_output_onto_a_run_directorys_files_is_refused(tmp_path, capsys):
    import yaml

    config = {
        "trainer": "native",
        "joints": 3,
        "n_envs": 2,
        "timesteps": 256,
        "eval_episodes": 1,
        "threads": 1,
        "ppo": {"n_steps": 128, "batch_size": 64, "n_epochs": 1},
        "env": {"max_episode_steps": 50},
    }
    (tmp_path / "tiny.yaml").write_text(yaml.safe_dump(config))
    run = tmp_path / "run"
    assert (
        run_cli(capsys, "train", "--config", tmp_path / "tiny.yaml", "--run-dir", run, "--no-progress")[0]
        == 0
    )
    evaluations = (run / "evaluations.csv").read_bytes()
    line = one_line_error(capsys, "evaluate", run, "--episodes", 1, "--json", run / "evaluations.csv")
    assert "which this command reads" in line
    assert (run / "evaluations.csv").read_bytes() == evaluations
    assert run_cli(capsys, "evaluate", run, "--episodes", 1, "--json", run / "eval.json")[0] == 0


# -- 5. SIGTERM and one-line errors ---------------------------------------------------------------------
def test_sigterm_unwinds_and_leaves_no_temporary_folder(exported, tmp_path):
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = {**os.environ, "TMPDIR": str(scratch)}
    env.pop("TORCHINDUCTOR_CACHE_DIR", None)
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "snakesim",
            "evaluate",
            str(exported),
            "--episodes",
            str(LIMITS["eval_episodes"]),
        ],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while not any(scratch.iterdir()) and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(2.0)  # into the episodes
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 143, err
    # (snakesim: terminated, when it came before the command started)
    assert err.endswith(": terminated\n") and err.count("\n") == 1, err
    assert list(scratch.iterdir()) == [], "the snakesim-torch-* folder is removed"


def test_error_lines_are_capped(tmp_path, capsys):
    long = tmp_path.joinpath(*["x" * 200] * 10, "model.zip")
    line = one_line_error(capsys, "evaluate", long)
    assert len(line) == LIMITS["error_chars"] and "..." in line
    assert line.startswith("snakesim evaluate: error: ") and line.endswith(
        "(expected a run directory or a model .zip)"
    )


# -- issue 57: statistics within bounds ------------------------------------------------------------------
class Call:
    """Pickled as a call of ``func`` with ``args`` (REDUCE): what a crafted file asks of what it names."""

    def __init__(self, func, *args) -> None:
        self.func, self.args = func, args

    def __reduce__(self):
        return (self.func, self.args)


_RESTORED: dict[int, tuple] = {}


def restored(cls, state):
    """An instance of ``cls`` that pickles as one restored from ``state`` (NEWOBJ, then BUILD), as a
    saved object is: what a crafted file can make of an allowed class."""
    obj = cls.__new__(cls)
    _RESTORED[id(obj)] = (obj, state)  # kept, so that its id is not reused
    return obj


class _Crafting(pickle.Pickler):
    def reducer_override(self, obj):
        if id(obj) in _RESTORED:
            return (copyreg.__newobj__, (type(obj),), _RESTORED[id(obj)][1])
        return NotImplemented


def crafted(obj, protocol: int = 4) -> bytes:
    buffer = io.BytesIO()
    _Crafting(buffer, protocol=protocol).dump(obj)
    return buffer.getvalue()


def bounded_child(code: str, *args, timeout=120) -> subprocess.CompletedProcess:
    """``code`` in a Python child whose address space may grow by at most 2 GiB once snakesim, SB3 and
    torch are imported (a statistics file asking for more fails there, not on this machine); it
    prints, last, how much its peak resident memory grew (MiB)."""
    prologue = (
        "import resource, sys\n"
        "import snakesim.agents.loading, snakesim.cli.app, stable_baselines3.common.vec_env, torch\n"
        "torch.set_num_threads(1)\n"
        "size = int(open('/proc/self/statm').read().split()[0]) * resource.getpagesize()\n"
        "resource.setrlimit(resource.RLIMIT_AS, (size + (2 << 30), resource.RLIM_INFINITY))\n"
        # VmHWM, not ru_maxrss: Linux carries ru_maxrss across exec, so a child of a large test process
        # would start at its parent's peak and hide its own growth.
        "hwm = lambda: int(next(l for l in open('/proc/self/status') if l.startswith('VmHWM')).split()[1])\n"
        "before = hwm()\n"
    )
    epilogue = "\nprint((hwm() - before) // 1024)\n"
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MALLOC_ARENA_MAX": "2"}
    return subprocess.run(
        [sys.executable, "-c", prologue + code + epilogue, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


def test_a_tiny_statistics_file_cannot_allocate_gigabytes(exported, tmp_path):
    """The issue's case: a VecNormalize pickle of a few dozen bytes holding RunningMeanStd(1e-4, (N,)),
    N = 3e8, allocated 3 GB before any check. Now `snakesim evaluate` refuses it in one line, the
    peak memory barely moves, and the library says the same."""
    from stable_baselines3.common.running_mean_std import RunningMeanStd
    from stable_baselines3.common.vec_env import VecNormalize

    model = tmp_path / "m.zip"
    model.write_bytes(exported.read_bytes())
    stats = tmp_path / "m_vecnormalize.pkl"
    stats.write_bytes(crafted(Call(RunningMeanStd, 1e-4, (300_000_000,))))
    assert len(stats.read_bytes()) < 100
    nested = tmp_path / "n.zip"
    nested.write_bytes(exported.read_bytes())
    (tmp_path / "n_vecnormalize.pkl").write_bytes(
        crafted(restored(VecNormalize, {"obs_rms": Call(RunningMeanStd, 1e-4, (300_000_000,))}))
    )
    done = bounded_child(
        "code = snakesim.cli.app.main(['evaluate', sys.argv[1], '--episodes', '1'])\n"
        "try:\n"
        "    snakesim.agents.load_agent(sys.argv[2])\n"
        "except snakesim.agents.AgentError as error:\n"
        "    print(error)\n"
        "print(code)",
        model,
        nested,
    )
    *printed, code, grew = done.stdout.splitlines()
    assert code == "1" and done.returncode == 0, done.stderr
    refusal = (
        "refused: the pickle builds RunningMeanStd of shape (300000000,): more than the model's 20 "
        "observations"
    )
    assert done.stderr == f"snakesim evaluate: error: {stats}: {refusal}\n"
    assert printed == [f"{tmp_path / 'n_vecnormalize.pkl'}: {refusal}"]
    assert int(grew) < 200, f"peak memory grew by {grew} MiB"


def test_a_statistics_file_refuses_each_way_to_ask_too_much(tmp_path):
    """Variants: each allowed callable asked for gigabytes, or for what a VecNormalize file never
    holds (objects, a dtype whose state makes its size 10 GB, a class changed, a stack-deep key), and the
    two steps of the C unpickler that allocate what a few bytes state (BYTEARRAY8's length, a
    LONG_BINPUT's memo index). Each is refused before it allocates, in a child that could not
    allocate 2 GiB more anyway."""
    import struct

    from gymnasium.spaces import Box
    from numpy._core.multiarray import _reconstruct, scalar
    from numpy.random import PCG64, SeedSequence
    from numpy.random._pickle import __generator_ctor as generator_ctor
    from stable_baselines3.common.running_mean_std import RunningMeanStd
    from stable_baselines3.common.vec_env import VecNormalize

    n = 300_000_000

    class Dtype:  # numpy.dtype("V8") given the state of a structured dtype of objects, 10 GB each
        def __reduce__(self):
            state = (3, "|", None, ("a",), {"a": (np.dtype("O"), 0)}, 10**10, 1, 27)
            return (np.dtype, ("V8", False, True), state)

    class Flags:  # float64 with the flag that says it holds objects
        def __reduce__(self):
            return (np.dtype, ("f8", False, True), (3, "<", None, None, None, -1, -1, 1))

    class ArrayState:  # an empty array given the state of 2.4 GB
        def __reduce__(self):
            return (_reconstruct, (np.ndarray, (0,), b"b"), (1, (n,), np.dtype("f8"), False, b"\0" * 8))

    shared = b"\0" * (1 << 20)

    class Swapped:  # one MiB of bytes, made into many big-endian arrays (copies) through the memo
        def __reduce__(self):
            return (_reconstruct, (np.ndarray, (0,), b"b"), (1, (1 << 17,), np.dtype(">f8"), False, shared))

    cases = {
        "box": (
            crafted(Call(Box, 0.0, 1.0, (n,))),
            "builds Box of shape (300000000,): more than the model's 20",
        ),
        "rms_int": (crafted(Call(RunningMeanStd, 1e-4, n)), "builds RunningMeanStd of shape (300000000,)"),
        "rms_shape": (
            crafted(Call(RunningMeanStd, 1e-4, "x" * 9)),
            "gives RunningMeanStd the shape 'xxxxxxxxx'",
        ),
        "vecnormalize": (crafted(Call(VecNormalize, None)), "builds VecNormalize from arguments"),
        "ndarray": (
            crafted(Call(np.ndarray, (n,), "f8")),
            "builds ndarray of shape (300000000,) (2,400,000,000 bytes)",
        ),
        "reconstruct": (
            crafted(Call(_reconstruct, np.ndarray, (n, 8), b"b")),
            "(2,400,000,000 bytes): more array data",
        ),
        "array_state": (crafted(ArrayState()), "a numpy array of shape (300000000,) (2,400,000,000 bytes)"),
        "swapped": (
            crafted([Swapped()] * 1 + [Swapped() for _ in range(20)]),
            "more array data than a statistics file holds (16 MiB",
        ),
        "objects": (
            crafted(Call(scalar, np.dtype("O"), None)),
            "the dtype 'object', which a VecNormalize file does not hold",
        ),
        "dtype_state": (crafted(Dtype()), "the dtype '|V8', which a VecNormalize file does not hold"),
        "dtype_flags": (crafted(Flags()), "gives a numpy dtype the state (3, '<', None, None, ..."),
        "generator": (
            crafted(Call(generator_ctor, n, np.ndarray)),
            "calls __generator_ctor with <class 'numpy.ndarray'>",
        ),
        "seed": (
            crafted(Call(SeedSequence, 1 << 100)),
            "calls SeedSequence, which a VecNormalize file restores",
        ),
        "pcg": (crafted(Call(PCG64, 1)), "calls PCG64, which a VecNormalize file restores from its state"),
        "class_attribute": (
            b"\x80\x04\x8c)stable_baselines3.common.running_mean_std\x8c\x0eRunningMeanStd\x93N}\x8c\x06update"
            b"\x8c\x01xs\x86b.",
            "sets the state of <class 'st...ngMeanStd'>",
        ),
        "dunder": (
            crafted(restored(RunningMeanStd, {"__class__": Box})),
            "sets attributes of RunningMeanStd",
        ),
        "deep_key": (b"\x80\x04}N" + b"\x85" * 1_000 + b"Ns.", "keys a dict by (((...),),)"),
        "sets": (b"\x80\x04(" + b"\x8f" * 1_100_000 + b"l.", "takes more than 1,000,000 steps"),
        "bytearray8": (
            b"\x80\x05\x96" + struct.pack("<Q", 3 << 30) + b"x.",
            "!is not a VecNormalize pickle: UnpicklingError: a bytearray of 3,221,225,472 bytes in a file "
            "of 13",
        ),
        "memo": (b"\x80\x04Nr" + struct.pack("<I", 2_000_000_000) + b"\x8c\x01x.", None),
        "exec": (crafted(Call(exec, "1")), "names builtins.exec, which a VecNormalize file does not hold"),
    }
    for name, (data, _) in cases.items():
        (tmp_path / f"{name}.pkl").write_bytes(data)
    done = bounded_child(
        "import json, pathlib\n"
        "from snakesim.agents.loading import AgentError, load_normalizer\n"
        "out = {}\n"
        "for path in sorted(pathlib.Path(sys.argv[1]).glob('*.pkl')):\n"
        "    try:\n"
        "        out[path.stem] = type(load_normalizer(path, 20)).__name__\n"
        "    except AgentError as error:\n"
        "        out[path.stem] = str(error)\n"
        "print(json.dumps(out))",
        tmp_path,
    )
    assert done.returncode == 0, done.stderr
    results, grew = json.loads(done.stdout.splitlines()[0]), int(done.stdout.splitlines()[1])
    for name, (_, message) in cases.items():
        got = results[name]
        if message is None:  # Python's unpickler keeps its memo in a dict: a far index costs nothing
            assert got.endswith("is not a VecNormalize pickle (it holds str)"), got
        elif message.startswith("!"):  # not a pickle: the C unpickler allocated the length it states
            assert got == f"{tmp_path / name}.pkl {message[1:]}", got
        else:
            assert got.startswith(f"{tmp_path / name}.pkl: refused: the pickle ") and message in got, (
                name,
                got,
            )
        assert "\n" not in got and len(got) < 300, got
    assert grew < 500, f"peak memory grew by {grew} MiB"  # a million sets are in it: 216 bytes each


def _statistics_of(normalizer) -> dict:
    rms = normalizer.obs_rms
    return {
        "mean": rms.mean.tolist(),
        "var": rms.var.tolist(),
        "count": float(rms.count),
        "returns": float(normalizer.ret_rms.var),
        "clip": normalizer.clip_obs,
        "epsilon": normalizer.epsilon,
        "old_obs": np.asarray(normalizer.old_obs).tolist(),
        "spaces": [str(normalizer.observation_space), str(normalizer.action_space)],
        "rng": normalizer.observation_space.np_random.bit_generator.state,
    }


@pytest.mark.parametrize("protocol", [3, 4, 5])
def test_real_statistics_load_as_sb3_loads_them(protocol, tmp_path):
    """What must still load, as SB3's own VecNormalize.load reads it: statistics of the largest batch
    (LIMITS['envs'] envs, randomized physics, so each env's info is in the file), with seeded spaces,
    in each protocol Python 3 writes."""
    from snakesim.envs.sb3 import SnakeVecEnv
    from stable_baselines3.common.vec_env import VecNormalize

    envs = LIMITS["envs"]
    saved = VecNormalize(SnakeVecEnv(envs, joints=3, randomize={"mass_scale": [0.9, 1.1]}))
    saved.reset()
    for _ in range(3):
        saved.step(np.zeros((envs, 3), np.float32))
    saved.observation_space.seed(5)
    saved.observation_space.sample()
    path = tmp_path / "vecnormalize.pkl"
    with open(path, "wb") as f:
        pickle.dump(saved, f, protocol=protocol)
    ours = load_normalizer(path, 8)
    theirs = VecNormalize.load(str(path), SnakeVecEnv(1, joints=3))
    assert _statistics_of(ours) == _statistics_of(theirs) and ours.training is False
    assert np.asarray(ours.old_obs).shape == (envs, 8) and float(ours.obs_rms.count) > 3 * envs


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"epsilon": float("nan")}, "its epsilon is not a number that keeps var + epsilon positive"),
        ({"epsilon": -1.0}, "its epsilon is not a number that keeps var + epsilon positive"),
        ({"epsilon": "1e-8"}, "its epsilon is not a number that keeps var + epsilon positive"),
        ({"clip_obs": 0.0}, "its clip_obs is not a positive number"),
        ({"clip_obs": float("nan")}, "its clip_obs is not a positive number"),
        ({"clip_obs": [10.0]}, "its clip_obs is not a positive number"),
        ({"norm_obs": "yes"}, "its norm_obs is not true or false"),
    ],
)
def test_statistics_that_would_normalise_to_nan_are_refused(exported, tmp_path, capsys, change, message):
    """Finite statistics of the right size are not enough: epsilon and clip_obs enter every normalised
    observation too (a NaN epsilon made every one NaN, silently)."""
    from snakesim.envs.sb3 import SnakeVecEnv
    from stable_baselines3.common.vec_env import VecNormalize

    model = tmp_path / "m.zip"
    model.write_bytes(exported.read_bytes())
    venv = SnakeVecEnv(1, **agents.load_agent(exported).env_kwargs)
    stats = VecNormalize.load(str(exported.parent / "goal-5_vecnormalize.pkl"), venv)
    for key, value in change.items():
        setattr(stats, key, value)
    stats.save(str(tmp_path / "m_vecnormalize.pkl"))
    line = one_line_error(capsys, "evaluate", model, "--episodes", 1)
    assert line.endswith(f"{tmp_path / 'm_vecnormalize.pkl'}: {message}"), line
    with pytest.raises(agents.AgentError, match=re.escape(message)):
        agents.load_agent(model)


# -- issue 57: torch's load errors in one line ------------------------------------------------------------
def _weights_of(path: Path) -> dict:
    import torch

    with zipfile.ZipFile(path) as archive:
        return torch.load(io.BytesIO(archive.read("policy.pth")), weights_only=True)


def _with_weights(path: Path, out: Path, state: dict) -> Path:
    import torch

    buffer = io.BytesIO()
    torch.save(state, buffer)
    return rewrite_zip(path, out, **{"policy.pth": buffer.getvalue()})


def _edited(state: dict, **changes) -> dict:
    out = dict(state)
    for name, value in changes.items():
        name = name.replace("__", ".")
        if value is None:
            del out[name]
        else:
            out[name] = value(out.get(name))
    return out


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        # The two: a sparse tensor (three lines of torch's text, no file), and a shape mismatch
        # ("Error(s) in loading state_dict for ActorCriticPolicy:").
        (
            {"action_net__weight": lambda t: t.to_sparse()},
            "tensor action_net.weight is a sparse_coo tensor; a policy's weights are dense",
        ),
        (
            {"value_net__weight": lambda t: t[:, :7].clone()},
            "the weights do not fit the network: tensor value_net.weight has shape [1, 7], expected [1, 64]",
        ),
        (
            {"action_net__weight": lambda t: t.to_sparse_csr()},
            "tensor action_net.weight is a sparse_csr tensor; a policy's weights are dense",
        ),
        (
            {"action_net__weight": lambda t: t.t().contiguous()},
            "the weights do not fit the network: tensor action_net.weight has shape [64, 3], expected "
            "[3, 64]",
        ),
        (
            {"log_std": lambda t: t[:, None].clone()},
            "the weights do not fit the network: tensor log_std has shape [3, 1], expected [3]",
        ),
        ({"log_std": None}, "the weights do not fit the network: no tensor log_std (expected shape [3])"),
        (
            {"extra__weight": lambda _: __import__("torch").zeros(2)},
            "the weights do not fit the network: tensor extra.weight is not one of its 13 (PPO-small, 20 "
            "observations)",
        ),
        (
            {"action_net__weight": lambda t: t.to(__import__("torch").int64)},
            "tensor action_net.weight holds int64 values, not floating-point weights",
        ),
        (
            {"action_net__weight": lambda t: __import__("torch").complex(t, t)},
            "tensor action_net.weight holds complex64 values, not floating-point weights",
        ),
        (
            {"action_net__weight": lambda t: t.to("meta")},
            "tensor action_net.weight holds no values (a meta tensor)",
        ),
        (
            # Finite in float64, infinite in the float32 network.
            {"action_net__bias": lambda t: t.double() * 1e300},
            "tensor action_net.bias holds NaN or infinite values",
        ),
    ],
)
@pytest.mark.filterwarnings("ignore:Sparse CSR tensor support is in beta state")  # making one here
def test_torch_load_errors_are_one_line_naming_file_member_and_tensor(
    exported, tmp_path, capsys, edit, message
):
    bad = _with_weights(exported, tmp_path / "bad.zip", _edited(_weights_of(exported), **edit))
    expected = f"{bad}: member policy.pth: {message}"
    code, out, err = run_cli(capsys, "evaluate", bad, "--episodes", 1)
    assert code == 1 and out == "" and err == f"snakesim evaluate: error: {expected}\n", err
    with pytest.raises(agents.AgentError) as error:
        agents.load_agent(bad)
    assert str(error.value) == expected


def test_a_policy_pth_torch_cannot_read_is_one_line(exported, tmp_path, capsys):
    """torch's paragraph (which suggests loading the file with weights_only=False) becomes its finding."""
    import torch

    tried = "member policy.pth: cannot load it with torch.load(weights_only=True): "
    for content, said in (
        (b"garbage", "UnpicklingError: Unsupported operand 103"),
        (
            pickle.dumps(print, protocol=2),
            "UnpicklingError: Unsupported global: GLOBAL print was not an allowed global",
        ),
        (
            b"PK\x03\x04" * 3,
            "RuntimeError: PytorchStreamReader failed reading zip archive: not a ZIP archive",
        ),
    ):
        bad = rewrite_zip(exported, tmp_path / "bad.zip", **{"policy.pth": content})
        line = one_line_error(capsys, "evaluate", bad, "--episodes", 1)
        assert line.startswith(f"snakesim evaluate: error: {bad}: {tried}{said}"), line
        assert "weights_only` set to `False`" not in line
    for state in ([1, 2], {"a": 1}, {1: torch.zeros(1)}):
        buffer = io.BytesIO()
        torch.save(state, buffer)
        bad = rewrite_zip(exported, tmp_path / "bad.zip", **{"policy.pth": buffer.getvalue()})
        said = (
            f"{bad}: member policy.pth: cannot load it as a policy: it holds no state dict (tensors by name)"
        )
        with pytest.raises(agents.AgentError, match=re.escape(said)):
            agents.load_agent(bad)


@pytest.mark.parametrize("dtype", ["float16", "bfloat16", "float64"])
def test_weights_of_any_float_precision_still_load(exported, tmp_path, dtype):
    # Read as float32, the network's (as load_state_dict did): the file's values, exactly where float32
    # holds them.
    import torch

    state = {k: v.to(getattr(torch, dtype)) for k, v in _weights_of(exported).items()}
    agent = agents.load_agent(_with_weights(exported, tmp_path / "w.zip", state))
    for name, tensor in agent.policy.state_dict().items():
        assert tensor.dtype == torch.float32
        np.testing.assert_array_equal(tensor.numpy(), state[name].float().numpy())


# -- issue 57: a randomize file is never quoted whole -----------------------------------------------------
SHADOW_LINE = "root:$6$abcdefghijklmnop$QWERTYUIOPasdfghjklzxcvbnm1234567890qwertyuiopA./:19000:0:99999:7:::"


@pytest.mark.parametrize(
    "text",
    [
        f"{SHADOW_LINE}\n",  # the issue's: the line alone (a key with no value, to YAML)
        f"mass_scale: [0.9, 1.1]\n{SHADOW_LINE}\n",
        f"mass_scale: '{SHADOW_LINE}'\n",
        f"mass_scale: ['{SHADOW_LINE}', 1.1]\n",
        f"'{SHADOW_LINE}': [0.9, 1.1]\n",
        f"mass_scale: [0.9, 1.1]\nmass_scale: '{SHADOW_LINE}'\n",
        f"mass_scale: [0.9,\n{SHADOW_LINE}\n",
    ],
)
def test_a_randomize_file_is_quoted_at_most_in_short_excerpts(tmp_path, capsys, text):
    """The issue's command, `snakesim evaluate models/goal-10.safetensors --randomize F.yaml`, on a
    file holding a password-hash line printed the line twice, uncut: now at most 24 characters of a
    value the file holds appear in the error (docs/formats.md), none of such a line."""
    rnd = tmp_path / "F.yaml"
    rnd.write_text(text)
    line = one_line_error(
        capsys, "evaluate", MODELS / "goal-10.safetensors", "--randomize", rnd, "--episodes", 1
    )
    assert "$6$" not in line and "QWERTY" not in line and "99999" not in line, line
    for quoted in re.findall(r"'([^']*)'|\"([^\"]*)\"|`([^`]*)`", line):
        assert len("".join(quoted)) <= 24, line
