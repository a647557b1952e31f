"""Misuse that must end in a result or a clear error: never a hang, a crash or a traceback."""

from __future__ import annotations

import errno
import json
import os
import pickle
import shutil
import subprocess
import sys
import textwrap
import zipfile

import gymnasium
import numpy as np
import pytest
import yaml
from snakesim import ENV_ID, SnakeEnv, SnakeVecEnv, SnakeVectorEnv
from snakesim.cli import app as cli
from snakesim.limits import LIMITS
from snakesim.runs import config as runconfig

# Each scenario runs in its own interpreter with a time limit: a deadlock fails the test, not CI.
_THREADS = textwrap.dedent(
    """
    import threading, numpy as np
    from snakesim import SnakeEnv, SnakeVecEnv

    def hammer(targets):
        errors = []
        def wrap(f):
            def run():
                try:
                    f()
                except Exception as e:  # a clear error is acceptable, a hang is not
                    errors.append(repr(e))
            return run
        ts = [threading.Thread(target=wrap(f)) for f in targets]
        [t.start() for t in ts]
        [t.join() for t in ts]
        return errors

    e = SnakeEnv(); e.reset(seed=0)
    def steps():
        for _ in range(1500):
            e.step(np.zeros(5, np.float32))
    def poses():
        for _ in range(1500):
            e.cube_poses(); e.goal
    def resets():
        for s in range(30):
            e.reset(seed=s)
    assert not hammer([steps, steps]), "step + step"
    assert not hammer([steps, poses]), "step + cube_poses"
    assert not hammer([resets, resets, steps]), "reset + reset + step"

    v = SnakeVecEnv(3); v.seed(0); v.reset()
    def vsteps():
        for _ in range(500):
            v.step_async(np.zeros((3, 5), np.float32)); v.step_wait()
    def vresets():
        for s in range(20):
            v.reset()
    hammer([vsteps, vsteps, vresets])
    print("done")
    """
)


def test_concurrent_use_from_threads_is_serialised_not_a_deadlock():
    proc = subprocess.run([sys.executable, "-c", _THREADS], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "done"


# -- silent infinities and limits --------------------------------------------------------------------
@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: SnakeEnv().reset(options={"start": (1e39, 0, 0.5, 0)}), "start must have |x| and |y|"),
        (lambda: SnakeEnv().reset(options={"start": (1e18, 0, 0.25, 0)}), "start must have |x| and |y|"),
        (lambda: SnakeEnv().reset(options={"start": (0, 0, -5, 0)}), "start z must be in [0, 100]"),
        (lambda: SnakeEnv().reset(options={"goal": (1e39, 0)}), "reset goal must have |x| and |y|"),
        (lambda: SnakeEnv(goal=(1e308, 1e308)), "goal: must have |x| and |y| at most 10000"),
        (lambda: SnakeEnv(reward={"progress_weight": 1e308}), "reward.progress_weight: must be in"),
        (lambda: SnakeEnv(reward={"success_reward": -1e7}), "reward.success_reward: must be in"),
        (lambda: SnakeEnv(start={"x": [-1e5, 0]}), "start.x: must lie within"),
        (
            lambda: SnakeEnv(physics_steps_per_env_step=2**31),
            "physics_steps_per_env_step: must be in [1, 240]",
        ),
        (lambda: SnakeEnv(max_episode_steps=10**12), "max_episode_steps: must be in [1, 10000000]"),
        (lambda: SnakeEnv(action_scale=1e300), "action_scale: must be in (0, 100]"),
        (lambda: SnakeVecEnv(10**9), "num_envs must be in [1, 1024]"),
        (lambda: SnakeVectorEnv(10**9), "num_envs must be in [1, 1024]"),
    ],
)
def test_values_beyond_the_limits_are_refused_naming_the_field(make, field):
    with pytest.raises(ValueError) as error:
        make()
    assert field in str(error.value)


def test_limits_come_from_the_rust_side():
    assert LIMITS["position"] == 1e4
    assert LIMITS["physics_steps_per_env_step"] == 240
    assert LIMITS["envs"] == 1024
    assert LIMITS["seed"] == 2**32 - 1


def test_the_largest_allowed_values_stay_finite():
    env = SnakeEnv(
        goal=(-1e4, 1e4), reward={"distance_weight": 1e6, "energy_weight": 1e6, "smoothness_weight": 1e6}
    )
    obs, _ = env.reset(seed=0, options={"start": (1e4, -1e4, 0.5, 0)})
    rng = np.random.default_rng(0)
    for _ in range(50):
        obs, reward, *_ = env.step(rng.uniform(-1, 1, 5).astype(np.float32))
        assert np.isfinite(obs).all() and np.isfinite(reward)
    assert abs(obs[0] - 1e4) < 2 and abs(obs[1] + 1e4) < 2  # the snake still lies on the plane, in place
    assert env.cube_poses()[:, 2].max() < 0.3


# -- config semantics ----------------------------------------------------------------------------
def test_gymnasium_make_max_episode_steps_is_the_episode_length():
    for steps in (6000, 7):
        env = gymnasium.make(ENV_ID, max_episode_steps=steps)
        env.reset(seed=0)
        for n in range(1, steps + 1):  # noqa: B007 - n is the step that ended the episode
            *_, terminated, truncated, _ = env.step(np.zeros(5, np.float32))
            if terminated or truncated:
                break
        assert (n, truncated) == (steps, True)
    assert gymnasium.make(ENV_ID).spec.max_episode_steps == 5000


def test_integer_actions_are_numbers():
    env = SnakeEnv()
    env.reset(seed=0)
    by_int = env.step(np.array([1, 0, -1, 0, 1]))[0]
    env.reset(seed=0)
    by_float = env.step(np.array([1.0, 0.0, -1.0, 0.0, 1.0], np.float32))[0]
    np.testing.assert_array_equal(by_int, by_float)
    with pytest.raises(TypeError, match="float32 or float64"):
        env.step(np.array(["a"] * 5))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_episode_steps": 2.9}, "max_episode_steps: invalid type: floating point"),
        ({"action_scale": "2"}, 'action_scale: invalid type: string "2"'),
        ({"goal": (True, False)}, "goal[0]: invalid type: boolean"),
        ({"reward": {"progress_weight": "a"}}, 'reward.progress_weight: invalid type: string "a"'),
        ({"start": {"yaw": [0, "x"]}}, "start.yaw[1]: invalid type: string"),
    ],
)
def test_wrong_types_are_type_errors_naming_the_key_path(kwargs, message):
    with pytest.raises(TypeError) as error:
        SnakeEnv(**kwargs)
    assert str(error.value).startswith(message.split(":")[0]) and message in str(error.value)


def test_set_parses_numbers_as_yaml_does():
    assert runconfig.parse_set(["ppo.learning_rate=3e-4", "ppo.gamma=0.99", "timesteps=4096"]) == {
        "ppo": {"learning_rate": 3e-4, "gamma": 0.99},
        "timesteps": 4096,
    }


def test_pickle_carries_the_configuration_and_says_so():
    env = gymnasium.make(ENV_ID, joints=3)
    env.reset(seed=0)
    env.step(np.zeros(3, np.float32))
    copy = pickle.loads(pickle.dumps(env))
    with pytest.raises(gymnasium.error.ResetNeeded, match="unpickled"):
        copy.step(np.zeros(3, np.float32))
    first, _ = copy.reset(seed=0)
    again, _ = gymnasium.make(ENV_ID, joints=3).reset(seed=0)
    np.testing.assert_array_equal(first, again)
    copy.step(np.zeros(3, np.float32))


# -- the snakesim command: one line, never a traceback ----------------------------------------------
TINY_SB3 = {
    "trainer": "sb3",
    "joints": 3,
    "n_envs": 2,
    "timesteps": 512,
    "eval_freq": 256,
    "eval_episodes": 1,
    "checkpoint_freq": 256,
    "normalize": True,
    "device": "cpu",
    "torch_threads": 1,
    "ppo": {"n_steps": 128, "batch_size": 128, "n_epochs": 1},
    "env": {"max_episode_steps": 50},
}


@pytest.fixture(scope="module")
def sb3_run(tmp_path_factory):
    root = tmp_path_factory.mktemp("hardening")
    config = root / "tiny.yaml"
    config.write_text(yaml.safe_dump(TINY_SB3))
    run_dir = root / "run"
    assert cli.main(["train", "--config", str(config), "--run-dir", str(run_dir), "--no-progress"]) == 0
    return run_dir


def _copy(run_dir, tmp_path, name="copy"):
    target = tmp_path / name
    shutil.copytree(run_dir, target)
    return target


def _rewrite_zip(path, member, content):
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    members[member] = content
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)


def _data_with(path, **spaces):
    with zipfile.ZipFile(path) as archive:
        data = json.loads(archive.read("data"))
    for key, shape in spaces.items():
        data[key]["_shape" if "_shape" in data[key] else "shape"] = shape
    return json.dumps(data).encode()


def _corrupt(case, run):
    """Damages the copy of a run as `case` says; returns the snakesim arguments that meet it."""
    model, checkpoints = run / "model.zip", sorted((run / "checkpoints").glob("model_*_steps.zip"))
    last = checkpoints[-1]
    if case == "garbage policy.pth":
        _rewrite_zip(model, "policy.pth", b"garbage")
        return ["evaluate", run, "--episodes", 1]
    if case == "shapes that lie":
        _rewrite_zip(model, "data", _data_with(model, observation_space=[99]))
        return ["evaluate", run, "--episodes", 1]
    if case == "shapes as strings":
        _rewrite_zip(model, "data", _data_with(model, observation_space=["a"]))
        return ["evaluate", run, "--episodes", 1]
    if case == "corrupt vecnormalize.pkl":
        (run / "vecnormalize.pkl").write_bytes(b"garbage")
        return ["replay", run, "--out", run / "r.png", "--seconds", 0.1]
    # A damaged checkpoint is skipped for the one before it (named in a note: test_writers.py); with
    # every one damaged, resuming is refused.
    if case == "truncated checkpoint zip":
        for zip_ in (run / "checkpoints").glob("model_*_steps.zip"):
            zip_.write_bytes(zip_.read_bytes()[:100])
        return ["train", "--run-dir", run, "--resume", "--timesteps", 1024, "--no-progress"]
    if case == "corrupt checkpoint json":
        for note in (run / "checkpoints").glob("model_*_steps.json"):
            note.write_text("{bad")
        return ["train", "--run-dir", run, "--resume", "--timesteps", 1024, "--no-progress"]
    if case == "corrupt checkpoint vecnormalize":
        next((run / "checkpoints").glob("vecnormalize_*_steps.pkl")).write_bytes(b"\x80\x04garbage")
        (run / "checkpoints" / f"vecnormalize_{last.stem.split('_')[1]}_steps.pkl").write_bytes(b"garbage")
        return ["train", "--run-dir", run, "--resume", "--timesteps", 1024, "--no-progress"]
    if case == "non-numeric evaluations row":
        with open(run / "evaluations.csv", "a") as f:
            f.write("x,y,z,1,2,3\n")
        return ["train", "--run-dir", run, "--resume", "--timesteps", 1024, "--no-progress"]
    raise AssertionError(case)


CORRUPT = {
    "garbage policy.pth": "cannot load",
    "shapes that lie": "expects 99 observations",
    "shapes as strings": "expected flat Box spaces",
    "corrupt vecnormalize.pkl": "is not a VecNormalize pickle",
    "truncated checkpoint zip": "none of its checkpoints loads (skipped a checkpoint: ",
    "corrupt checkpoint json": "is corrupt",
    "corrupt checkpoint vecnormalize": "is not a VecNormalize pickle",
    "non-numeric evaluations row": "is not an evaluation row",
}


def _one_line_error(capsys, argv, code=1):
    try:
        got = cli.main([str(a) for a in argv])
    except SystemExit as stop:  # argparse's usage errors
        got = stop.code
    _, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert got == code, err
    assert len(lines) == 1 and "error:" in lines[0], err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("case", sorted(CORRUPT))
def test_corrupt_files_are_one_line(case, sb3_run, tmp_path, capsys):
    argv = _corrupt(case, _copy(sb3_run, tmp_path))
    assert CORRUPT[case] in _one_line_error(capsys, argv)


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        (["evaluate", "{run}", "--seed", 2**64], 2, "--seed: expected an integer <= 4294967295"),
        (["evaluate", "{run}", "--torch-threads", 100000], 2, "--torch-threads: expected an integer <= 256"),
        (["evaluate", "{run}", "--episodes", 10**9], 2, "--episodes: expected an integer <= 100000"),
        (["replay", "{run}", "--fps", 1e-9, "--out", "{tmp}/m.gif"], 1, "--fps must be in [0.1, 50]"),
        (["replay", "{run}", "--fps", 1e9, "--out", "{tmp}/m.gif"], 1, "--fps must be in [0.1, 50]"),
        (
            ["replay", "{run}", "--panels", 10**6, "--out", "{tmp}/m.png"],
            2,
            "--panels: expected an integer <= 24",
        ),
        (["replay", "{run}", "--out", "{tmp}/m.gif", "--out", "{tmp}/./m.gif"], 1, "name the same file"),
        (["train", "--seed", 2**32, "--run-dir", "{tmp}/seeded"], 2, "--seed: expected an integer <= 4294"),
        (["train", "--n-envs", 100000, "--run-dir", "{tmp}/wide"], 1, "n_envs: must be in [1, 1024]"),
        (
            ["train", "--set", "env.max_episode_steps=1e30", "--run-dir", "{tmp}/long"],
            1,
            "env.max_episode_steps",
        ),
    ],
)
def test_bad_arguments_are_one_line(argv, code, message, sb3_run, tmp_path, capsys):
    argv = [str(a).format(run=sb3_run, tmp=tmp_path) for a in argv]
    assert message in _one_line_error(capsys, argv, code)
    # Refused before anything was created: a rerun or --resume is not blocked by a half-made run dir.
    assert not any(tmp_path.iterdir())


def test_a_full_disk_is_one_line_and_keeps_the_old_file(sb3_run, tmp_path, capsys, monkeypatch):
    import snakesim.viewer.plots

    out = tmp_path / "fig.png"
    out.write_bytes(b"precious")

    def full_disk(runs, path, **kwargs):
        with open(path, "wb") as f:
            f.write(b"half a figure")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(snakesim.viewer.plots, "plot_runs", full_disk)
    line = _one_line_error(capsys, ["plot", sb3_run, "--out", out])
    assert "No space left on device" in line
    assert out.read_bytes() == b"precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]


def test_an_unexpected_error_is_one_line_too(sb3_run, tmp_path, capsys, monkeypatch):
    import snakesim.viewer.plots

    def broken(*args, **kwargs):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(snakesim.viewer.plots, "plot_runs", broken)
    line = _one_line_error(capsys, ["plot", sb3_run, "--out", tmp_path / "f.png"])
    assert "ZeroDivisionError: a bug" in line and "SNAKESIM_TRACEBACK" in line
