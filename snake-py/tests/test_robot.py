"""SnakeEnv on URDF robots (the ``robot`` keyword)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import snakesim

ROBOTS = Path(__file__).resolve().parents[2] / "robots"


def test_paper_robot_file_is_the_built_in_env():
    a = snakesim.SnakeEnv(joints=5, max_episode_steps=300)
    b = snakesim.SnakeEnv(robot=ROBOTS / "paper-cubes-5.yaml", max_episode_steps=300)
    assert a.observation_space == b.observation_space and a.action_space == b.action_space
    oa, _ = a.reset(seed=7)
    ob, _ = b.reset(seed=7)
    assert oa.tobytes() == ob.tobytes()
    rng = np.random.default_rng(0)
    for _ in range(300):
        action = rng.uniform(-1, 1, 5).astype(np.float32)
        ra, rb = a.step(action), b.step(action)
        assert ra[0].tobytes() == rb[0].tobytes()
        assert ra[1:4] == rb[1:4]


def test_spaces_follow_the_robot():
    env = snakesim.SnakeEnv(robot=str(ROBOTS / "wheeled-8.yaml"), max_episode_steps=20)
    assert env.action_space.shape == (23,)
    assert env.observation_space.shape == (2 + 2 * 23,)
    # The goal task's wave actions (steering, amplitude, frequency) and extended observation with the
    # wave's phase.
    goal = snakesim.SnakeGoalEnv(robot=ROBOTS / "wheeled-8.yaml")
    assert goal.action_space.shape == (3,)
    assert goal.observation_space.shape == (2 + 2 * 23 + 6 + 2,)
    obs, _ = env.reset(seed=1)
    assert env.observation_space.contains(obs)
    assert env._env.cube_poses().shape == (24, 7)


def test_a_missing_robot_is_one_clear_error():
    with pytest.raises(ValueError, match="nowhere.urdf: cannot read"):
        snakesim.SnakeEnv(robot="nowhere.urdf")


def test_a_recorded_robot_episode_draws_its_links(tmp_path):
    rr = pytest.importorskip("rerun")
    from snakesim.envs.wrappers import RerunLogger

    recording = rr.RecordingStream("snakesim-test")
    recording.save(tmp_path / "robot.rrd")
    env = RerunLogger(
        snakesim.SnakeEnv(robot=ROBOTS / "wheeled-8.yaml", max_episode_steps=30), recording=recording
    )
    env.reset(seed=0)
    for _ in range(30):
        env.step(env.action_space.sample())
    env.close()
    recording.disconnect()
    reader = rr.chunk.RrdReader(tmp_path / "robot.rrd")
    paths = {str(chunk.entity_path) for chunk in reader.stream()}
    assert {"/world/snake/link0", "/world/snake/link23", "/world/snake/link1/shape0"} <= paths
