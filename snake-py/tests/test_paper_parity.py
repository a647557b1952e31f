"""snakesim.SnakeEnv against the paper's env rebuilt in pybullet 3.2.7, bit for bit, through Python.

tests/env_parity.rs checks the Rust env the same way; this checks the whole Python path (argument
handling, numpy conversion, gymnasium.make) on top of it.
"""

import csv
import json
import subprocess
import sys

import gymnasium
import numpy as np
import pytest
import snakesim  # noqa: F401  (registers the env)


def reference(repo, tmp_path, spec):
    (tmp_path / "spec.json").write_text(json.dumps(spec))
    script = repo / "tests" / "reference" / "paper_env_reference.py"
    subprocess.run(
        [sys.executable, str(script), str(tmp_path / "spec.json"), str(tmp_path)],
        check=True,
        capture_output=True,
    )
    tables = {}
    for env in spec["envs"]:
        for k in range(len(env["episodes"])):
            with open(tmp_path / f"{env['name']}-{k}.csv") as f:
                rows = list(csv.reader(f))[1:]
            tables[(env["name"], k)] = [[float(c) for c in row] for row in rows]
    return tables


@pytest.mark.parametrize("joints", [5, 10])
def test_paper_env_parity(repo, tmp_path, joints):
    rng = np.random.default_rng(joints)
    starts = [[0.1, -0.3, 0.5, 0.15], [-0.45, 0.2, 0.5, -0.19]]
    episodes = []
    for start in starts:
        # Smooth-ish random actions, some beyond [-1, 1] to exercise clipping.
        actions = np.cumsum(rng.normal(0, 0.2, (600, joints)), axis=0).astype(np.float32)
        episodes.append({"start": start, "goal": [0, -10], "actions": actions.tolist()})
    # One that reaches a goal placed just ahead of the snake: the 100 reward and termination.
    gait = [[0.4 * np.sin(2 * np.pi * (t / 360 - j / 8)) for j in range(joints)] for t in range(1500)]
    episodes.append({"start": [0, 0, 0.5, 0], "goal": [0, -2.5], "actions": np.float32(gait).tolist()})
    spec = {
        "envs": [{"name": f"p{joints}", "joints": joints, "max_episode_steps": 5000, "episodes": episodes}]
    }
    tables = reference(repo, tmp_path, spec)

    env = gymnasium.make("snakesim/Snake-v0", joints=joints, preset="snakebot-gym")
    for k, episode in enumerate(episodes):
        rows = tables[(f"p{joints}", k)]
        obs, _ = env.reset(options={"start": episode["start"], "goal": episode["goal"]})
        assert obs.astype(np.float64).tolist() == rows[0][4:], f"episode {k}: first observation"
        for step, action in enumerate(episode["actions"][: len(rows) - 1], start=1):
            obs, reward, terminated, truncated, _ = env.step(np.asarray(action, dtype=np.float32))
            row = rows[step]
            assert obs.astype(np.float64).tolist() == row[4:], f"episode {k} step {step}: observation"
            assert reward == row[1], f"episode {k} step {step}: reward {reward!r} != {row[1]!r}"
            assert (terminated, truncated) == (bool(row[2]), bool(row[3]))
        if k == 2:
            assert terminated and reward == 100.0, "the goal episode reaches the goal"
