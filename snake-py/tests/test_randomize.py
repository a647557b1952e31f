"""Randomized physics (the env keyword ``randomize``, issue 47 item 2) from Python."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import snakesim

NOMINAL = {
    "ground_friction": [0.5, 0.5],
    "mass_scale": [1.0, 1.0],
    "effort_scale": [1.0, 1.0],
    "kp_scale": [1.0, 1.0],
    "kd_scale": [1.0, 1.0],
    "latency_steps": [0, 0],
    "obs_noise": [0.0, 0.0],
}
WIDE = {
    "ground_friction": [0.3, 0.9],
    "mass_scale": [0.8, 1.2],
    "effort_scale": [0.7, 1.0],
    "kp_scale": [0.8, 1.2],
    "kd_scale": [0.8, 1.2],
    "latency_steps": [0, 2],
    "obs_noise": [0.0, 0.02],
}


def rollout(env, seed: int, steps: int):
    obs, info = env.reset(seed=seed)
    out = [obs.copy()]
    rng = np.random.default_rng(0)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(
            env.action_space.sample() * 0 + rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        )
        out += [obs.copy(), np.float64(reward), terminated, truncated, info["distance"]]
        if terminated or truncated:
            obs, _ = env.reset()
            out.append(obs.copy())
    return out


def test_zero_width_is_the_plain_env_bit_for_bit():
    a = rollout(snakesim.SnakeGoalEnv(joints=5), 3, 200)
    b = rollout(snakesim.SnakeGoalEnv(joints=5, randomize=NOMINAL), 3, 200)
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert np.array_equal(np.asarray(x), np.asarray(y))


def test_reset_info_holds_the_drawn_physics_under_the_given_keys():
    env = snakesim.SnakeGoalEnv(joints=4, randomize=WIDE)
    _, info = env.reset(seed=5)
    physics = info["physics"]
    assert set(physics) == set(WIDE)
    for key, (low, high) in WIDE.items():
        assert low <= physics[key] <= high
    assert isinstance(physics["latency_steps"], int)
    _, again = snakesim.SnakeGoalEnv(joints=4, randomize=WIDE).reset(seed=5)
    assert again["physics"] == physics
    _, other = env.reset(seed=6)
    assert other["physics"] != physics
    _, partial = snakesim.SnakeGoalEnv(joints=4, randomize={"mass_scale": [2.0, 2.0]}).reset(seed=1)
    assert partial["physics"] == {"mass_scale": 2.0}
    _, plain = snakesim.SnakeGoalEnv(joints=4).reset(seed=1)
    assert "physics" not in plain


@pytest.mark.parametrize(
    ("randomize", "message"),
    [
        ({"mass_scale": [1.2, 0.8]}, "randomize.mass_scale: must have low <= high"),
        ({"effort_scale": [float("nan"), 1.0]}, "randomize.effort_scale[0]: must be finite"),
        ({"kp_scale": [-1.0, 1.0]}, "randomize.kp_scale: must lie within"),
        ({"latency_steps": [0, 33]}, "randomize.latency_steps: must lie within"),
        ({"latency_steps": [0, 1.5]}, "randomize.latency_steps: must be whole env steps"),
        ({"skin_friction_scale": [1, 1]}, "randomize.skin_friction_scale: needs a body with skin friction"),
        ({"mass": [1, 2]}, "mass"),
    ],
)
def test_bad_ranges_are_one_line_value_errors(randomize, message):
    with pytest.raises(ValueError, match="randomize") as error:
        snakesim.SnakeGoalEnv(joints=3, randomize=randomize)
    text = str(error.value)
    assert message in text
    assert "\n" not in text


def test_evaluate_under_a_distribution(tmp_path):
    spec = tmp_path / "wide.yaml"
    spec.write_text("mass_scale: [0.8, 1.2]\nground_friction: [0.25, 1.0]\nlatency_steps: [0, 1]\n")
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakesim",
            "evaluate",
            "models/goal-10.safetensors",
            "--randomize",
            str(spec),
            "--episodes",
            "4",
            "--json",
            "-",
        ],
        capture_output=True,
        text=True,
        check=False,
        cwd=snakesim.__file__.rsplit("/snake-py/", 1)[0],
    )
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["randomize"] == {
        "mass_scale": [0.8, 1.2],
        "ground_friction": [0.25, 1.0],
        "latency_steps": [0, 1],
    }
    assert report["episodes"] == 4
    # Each episode's draws, to tell which physics cost a failure.
    for episode in report["per_episode"]:
        physics = episode["physics"]
        assert list(physics) == ["ground_friction", "mass_scale", "latency_steps"]
        assert 0.25 <= physics["ground_friction"] <= 1.0 and physics["latency_steps"] in (0, 1)
    bad = tmp_path / "bad.yaml"
    bad.write_text("mass_scale: [1.2, 0.8]\n")
    out = tmp_path / "out.json"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakesim",
            "evaluate",
            "models/goal-10.safetensors",
            "--randomize",
            str(bad),
            "--episodes",
            "4",
            "--json",
            str(out),
        ],
        capture_output=True,
        text=True,
        check=False,
        cwd=snakesim.__file__.rsplit("/snake-py/", 1)[0],
    )
    assert run.returncode != 0
    assert "randomize.mass_scale" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_the_vector_envs_report_each_episodes_physics():
    """``infos["physics"]`` of the native vector envs: every env's draw at reset, the autoreset envs'
    in step, each env's equal to a single env's seeded ``s + i`` (the Rust vector env's own test holds
    the episodes bit for bit)."""
    import gymnasium
    from snakesim.envs.sb3 import SnakeVecEnv
    from snakesim.envs.vector import SnakeVectorEnv

    kwargs = {"task": "goal", "joints": 5, "max_episode_steps": 3}
    kwargs["randomize"] = {"mass_scale": [0.5, 1.5], "latency_steps": [0, 2]}
    vec = SnakeVectorEnv(3, **kwargs)
    _, infos = vec.reset(seed=11)
    assert list(infos["_physics"]) == [True] * 3
    single = {k: v for k, v in kwargs.items() if k != "task"}
    for i in range(3):
        _, info = gymnasium.make("snakesim/SnakeGoal-v0", **single).reset(seed=11 + i)
        assert infos["physics"]["mass_scale"][i] == info["physics"]["mass_scale"]
        assert infos["physics"]["latency_steps"][i] == info["physics"]["latency_steps"]
    zeros = np.zeros((3, 3), np.float32)
    for _ in range(2):
        _, _, _, _, infos = vec.step(zeros)
        assert "physics" not in infos
    _, _, _, truncated, infos = vec.step(zeros)
    assert truncated.all() and list(infos["_physics"]) == [True] * 3
    draws = infos["physics"]["mass_scale"]
    assert all(0.5 <= m <= 1.5 for m in draws) and len(set(draws)) == 3

    sb3 = SnakeVecEnv(2, **kwargs)
    sb3.seed(11)
    sb3.reset()
    assert [i["physics"]["mass_scale"] for i in sb3.reset_infos] == list(
        SnakeVectorEnv(2, **kwargs).reset(seed=11)[1]["physics"]["mass_scale"]
    )
    for _ in range(3):
        sb3.step_async(np.zeros((2, 3), np.float32))
        _, _, dones, step_infos = sb3.step_wait()
    assert dones.all() and all("physics" in info for info in step_infos)
    assert SnakeVectorEnv(2, task="goal", joints=5).reset(seed=1)[1] == {}


def test_evaluation_lists_each_episodes_physics():
    """``run_episodes`` (snakesim evaluate's episodes) gives each episode the physics its reset drew:
    env i's first episode a single env's seeded ``s + i``, its second the draw of that env's
    ``reset()`` after the first, whatever the first's length (the noise has a stream of its own)."""
    import gymnasium
    from snakesim.agents.evaluation import run_episodes

    kwargs = {"task": "goal", "joints": 5, "max_episode_steps": 4}
    kwargs["randomize"] = {"mass_scale": [0.5, 1.5], "obs_noise": [0.0, 0.01]}
    single = {k: v for k, v in kwargs.items() if k != "task"}
    n = gymnasium.make("snakesim/SnakeGoal-v0", **single).action_space.shape[0]
    zeros = lambda obs: np.zeros((len(obs), n), np.float32)  # noqa: E731
    # 17 episodes over 16 envs: env 15 runs two, listed last.
    done = run_episodes(zeros, kwargs, 17, 3)
    expected = []
    for i in range(16):
        env = gymnasium.make("snakesim/SnakeGoal-v0", **single)
        _, info = env.reset(seed=3 + i)
        expected.append(info["physics"])
    env.step(np.zeros(n, np.float32))  # one step, where run_episodes' env ran four
    expected.append(env.reset()[1]["physics"])
    assert [e["physics"] for e in done] == expected
    assert expected[16] != expected[15]
    plain = {k: v for k, v in kwargs.items() if k != "randomize"}
    assert all("physics" not in e for e in run_episodes(zeros, plain, 2, 3))


# -- training under a distribution, end to end, with each trainer --------------------------------------
DISTRIBUTION = {
    "ground_friction": [0.3, 0.9],
    "latency_steps": [0, 2],
    "mass_scale": [0.8, 1.2],
    "obs_noise": [0.0, 0.01],
}
# Rollouts of 4 envs x 128 steps, episodes of at most 200 steps (test_native.py's and test_cli.py's
# tiny runs): about a second with either trainer.
TINY_RUN = {
    "joints": 3,
    "n_envs": 4,
    "timesteps": 1024,
    "eval_freq": 512,
    "eval_episodes": 2,
    "checkpoint_freq": 512,
    "ppo": {"n_steps": 128, "batch_size": 128, "n_epochs": 2},
    "env": {"max_episode_steps": 200},
}
TRAINER = {
    "native": {"trainer": "native", "threads": 2},
    "sb3": {"trainer": "sb3", "device": "cpu", "torch_threads": 1},
}


def _train(base, config) -> tuple[int, object]:
    import yaml
    from snakesim.cli import app as cli

    base.mkdir()
    path = base / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    run = base / "run"
    return cli.main(["train", "--config", str(path), "--run-dir", str(run), "--no-progress"]), run


def _weights(run, trainer: str) -> list[np.ndarray]:
    if trainer == "native":
        from safetensors.numpy import load_file

        return [v for _, v in sorted(load_file(run / "model.safetensors").items())]
    from snakesim.agents.loading import load_agent

    return [p.detach().numpy().copy() for p in load_agent(run).policy.parameters()]


@pytest.mark.parametrize("trainer", ["native", "sb3"])
def test_training_under_a_distribution_end_to_end(trainer, tmp_path, capsys):
    """A tiny run with ``env: {randomize: ...}`` with each trainer: it finishes and trains on the
    distribution (its weights differ from the same run's on the plain env), the model (native: its file's
    metadata; SB3: the run directory's config.yaml) records the distribution, and ``snakesim evaluate``
    and the Python API evaluate it under its own distribution and under another (``--randomize FILE``,
    ``env_overrides``)."""
    import yaml
    from snakesim.agents.evaluation import evaluate
    from snakesim.agents.loading import load_agent
    from snakesim.cli import app as cli
    from snakesim.envs.env import make_env
    from snakesim.runs import config as runconfig

    if trainer == "sb3":
        pytest.importorskip("stable_baselines3")
    config = {**TINY_RUN, **TRAINER[trainer], "env": {**TINY_RUN["env"], "randomize": DISTRIBUTION}}
    code, run = _train(tmp_path / "randomized", config)
    assert code == 0, capsys.readouterr().err
    code, plain = _train(tmp_path / "plain", {**TINY_RUN, **TRAINER[trainer]})
    assert code == 0, capsys.readouterr().err
    evaluations = (run / "evaluations.csv").read_text().splitlines()
    assert len(evaluations) == 3, "a header and an evaluation at 512 and 1024 timesteps"
    assert any(not np.array_equal(a, b) for a, b in zip(_weights(run, trainer), _weights(plain, trainer))), (
        "the randomized run trained on other episodes than the plain env's"
    )

    # What records the distribution: the run's config.yaml, and a native model file's own metadata.
    assert runconfig.load(run / "config.yaml")["env"]["randomize"] == DISTRIBUTION
    if trainer == "native":
        from safetensors import safe_open

        for model in [run / "model.safetensors", *(run / "checkpoints").glob("*.safetensors")]:
            with safe_open(model, "np") as f:
                assert json.loads(f.metadata()["env"])["randomize"] == DISTRIBUTION, model
            assert load_agent(model).env_kwargs["randomize"] == DISTRIBUTION, model
    agent = load_agent(run)
    assert agent.env_kwargs["randomize"] == DISTRIBUTION
    if trainer == "sb3":
        # A zip copied out of its run keeps its distribution (the env keywords travel in the zip).
        import shutil

        bare = Path(shutil.copy(run / "model.zip", tmp_path / "bare.zip"))
        assert load_agent(bare).env_kwargs["randomize"] == DISTRIBUTION

    # snakesim evaluate: under the model's own distribution, then under a file's.
    other = {"mass_scale": [0.5, 0.5], "latency_steps": [3, 3]}
    spec = tmp_path / "other.yaml"
    spec.write_text(yaml.safe_dump(other))
    reports = []
    for extra in ([], ["--randomize", str(spec)]):
        out = tmp_path / f"report{len(reports)}.json"
        argv = ["evaluate", str(run), "--episodes", "2", "--json", str(out), *extra]
        assert cli.main(argv) == 0, capsys.readouterr().err
        reports.append(json.loads(out.read_text()))
    assert reports[0]["randomize"] == DISTRIBUTION and reports[1]["randomize"] == other
    assert [r["episodes"] for r in reports] == [2, 2]
    assert reports[0]["mean_return"] != reports[1]["mean_return"], "other physics, other episodes"

    # The Python API: the agent's env draws from the given distribution, and evaluates there.
    agent = load_agent(run, env_overrides={"randomize": other})
    _, info = make_env(**agent.env_kwargs).reset(seed=3)
    assert info["physics"] == {"mass_scale": 0.5, "latency_steps": 3}
    result = evaluate(agent, 2, seed=reports[1]["seed"])
    assert len(result["per_episode"]) == 2
    assert result["mean_return"] == reports[1]["mean_return"], "the API evaluates as the command does"
