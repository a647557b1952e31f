"""Initialisation by imitation (the run configuration's ``init`` table) through ``snakesim train``:
bad tables are one-line refusals that create nothing, and a tiny run logs the ``init/`` scalars and
evaluates the fitted policy at 0 timesteps."""

import csv
import json

import numpy as np
import pytest
import yaml
from snakesim.cli import app as cli

# About a second: 2 envs, 512 controller steps, 2 rollouts of 256, episodes of at most 100 steps.
TINY = {
    "trainer": "native",
    "joints": 3,
    "n_envs": 2,
    "timesteps": 1024,
    "eval_freq": 512,
    "eval_episodes": 2,
    "checkpoint_freq": 512,
    "threads": 2,
    "normalize": True,
    "ppo": {"n_steps": 256, "batch_size": 64, "n_epochs": 2},
    "env": {"max_episode_steps": 100},
    "init": {"imitate": "steered_sine", "steps": 512, "epochs": 3, "batch_size": 64, "critic": True},
}


def train(tmp_path, capsys, config, *extra):
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    run_dir = tmp_path / "run"
    code = cli.main(["train", "--config", str(path), "--run-dir", str(run_dir), "--no-progress", *extra])
    out, err = capsys.readouterr()
    return code, out, err, run_dir


@pytest.mark.parametrize(
    ("init", "extra", "message"),
    [
        ({"imitate": "wiggle"}, [], "init.imitate: unknown controller 'wiggle' (expected one of: sine,"),
        (
            {"imitate": "steer", "hold": {"amplitude": 2}},
            ["--set", "env.task=goal"],
            "init.hold.amplitude: must be",
        ),
        ({"imitate": "sine", "steps": 0}, [], "init.steps: must be in [1, 4194304], got 0"),
        ({"imitate": "sine", "steps": 10**9}, [], "init.steps: must be in [1, 4194304]"),
        ({"imitate": "sine"}, ["--set", "env.task=goal"], "init.imitate: sine sets joint targets"),
        ({"imitate": "sine"}, ["--trainer", "sb3"], "init: only the native trainer"),
    ],
)
def test_bad_init_tables_are_one_line_and_create_nothing(init, extra, message, tmp_path, capsys):
    code, _, err, run_dir = train(tmp_path, capsys, {**TINY, "init": init}, *extra)
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and lines[0].startswith("snakesim"), err
    assert message in lines[0], lines[0]
    assert not run_dir.exists(), "nothing is created for a refused run"


def test_a_run_with_init_logs_it_and_evaluates_the_fitted_policy(tmp_path, capsys):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    code, _, err, run_dir = train(tmp_path, capsys, TINY)
    assert code == 0, err
    assert "init: imitated steered_sine for 512 env steps" in err
    events = EventAccumulator(str(run_dir / "tb" / "PPO_1"))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert {"init/bc_loss", "init/critic_loss", "init/seconds", "init/controller_ep_rew_mean"} <= tags
    bc = [e.value for e in events.Scalars("init/bc_loss")]
    assert [e.step for e in events.Scalars("init/bc_loss")] == [0, 1, 2, 3]
    assert bc[-1] < bc[0], bc
    with open(run_dir / "evaluations.csv") as f:
        steps = [int(row["timesteps"]) for row in csv.DictReader(f)]
    assert steps == [0, 512, 1024]
    saved = yaml.safe_load((run_dir / "config.yaml").read_text())
    assert saved["init"]["imitate"] == "steered_sine"


# -- the imitated controllers as baselines ------------------------------------------------------------
def snake_py_wave(front: float, joints: int, steering: float = 0.0) -> np.ndarray:
    """pybullet snake.py's joint targets at wave front ``front`` (its loop body, written out in
    numpy): amplitude 0.4 rad, wave length 4 m, segments of 0.5 m, ramped in over 4 segments."""
    ramp_end = 0.5 * 4
    scale = front / ramp_end if front < ramp_end else 1.0
    phase = (front - np.arange(1, joints + 1) * 0.5) / 4.0
    phase = (phase - np.floor(phase)) * 2 * np.pi
    t = np.sin(phase) * scale * 0.4
    if steering > 0:
        t = np.where(t < 0, t / (1 + steering), t)
    if steering < 0:
        t = np.where(t > 0, t / (1 - steering), t)
    return t + steering


@pytest.mark.parametrize("name", ["sine", "steered_sine"])
def test_baseline_sines_are_snake_py_waves_restarted_with_each_episode(name):
    """``baseline:sine``'s actions in the evaluation protocol are snake.py's wave over the action
    scale, its front advanced one env step per call and started over in each env whose episode ended
    (20 episodes of 7 steps in 16 envs: four envs run two); steered, the offset follows the base's x."""
    from snakesim.agents.evaluation import run_episodes
    from snakesim.agents.loading import load_agent
    from snakesim.envs.env import make_env

    agent = load_agent(f"baseline:{name}", joints=4, task="paper", env_overrides={"max_episode_steps": 7})
    config = make_env(**agent.env_kwargs).config
    per_step = config["snake"]["dt"] * config["physics_steps_per_env_step"] / 1.5 * 4.0
    goal_x, scale = config["goal"][0], config["action_scale"]
    calls: list[tuple[np.ndarray, np.ndarray]] = []
    restarts: list[tuple[int, int]] = []

    def act(obs):
        actions = agent.act(obs)
        calls.append((obs.copy(), np.asarray(actions, np.float64)))
        return actions

    def restart(env):
        restarts.append((len(calls), env))
        agent.restart(env)

    done = run_episodes(act, agent.env_kwargs, 20, 5, restart)
    assert [e["steps"] for e in done] == [7] * 20
    assert sorted({env for _, env in restarts}) == list(range(16))
    steps = np.zeros(16, int)
    for k, (obs, actions) in enumerate(calls):
        for env, row in enumerate(obs):
            steering = 0.0 if name == "sine" else float(np.clip(0.15 * (float(row[0]) - goal_x), -0.3, 0.3))
            expected = np.clip(snake_py_wave(steps[env] * per_step, 4, steering) / scale, -1, 1)
            np.testing.assert_allclose(actions[env], expected, atol=1e-6, err_msg=f"{k}: {env}")
        steps += 1
        for _, env in (r for r in restarts if r[0] == k + 1):
            steps[env] = 0
    # Every env ran its first episode and restarted at call 7; four of them ran a second one.
    assert len(calls) == 14 and sorted({k for k, _ in restarts}) == [7, 14]


def test_baseline_sine_evaluates_and_refuses_the_wrong_env(tmp_path, capsys):
    """``snakesim evaluate baseline:steered_sine --env paper`` reaches the paper's goal at 10 joints; on
    the goal task (gait actions) it is one line naming the action mode."""
    out = tmp_path / "e.json"
    args = ["evaluate", "baseline:steered_sine", "--env", "paper", "--joints", "10"]
    args += ["--preset", "snakebot-gym"]
    assert cli.main([*args, "--episodes", "2", "--seed", "900000", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["success_rate"] == 1.0
    capsys.readouterr()
    assert cli.main(["evaluate", "baseline:sine", "--joints", "5", "--episodes", "1"]) != 0
    err = capsys.readouterr().err.strip()
    assert "needs action mode 'joints'" in err and "\n" not in err
