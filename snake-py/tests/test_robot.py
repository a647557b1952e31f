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


def test_render_draws_a_robots_shapes_from_above():
    """render() of a robot draws each collision shape's outline seen from above: the pixel areas of a
    box, a lying cylinder, a sphere and a standing capsule match their geometric footprints (to the
    pixels along the outline), where the built-in snake's cube squares would not."""
    from snakesim.envs.render import BODY, HEAD, top_down

    q_yaw = [0.0, 0.0, np.sin(0.3), np.cos(0.3)]  # 0.6 rad about z
    q_lying = [0.0, np.sin(np.pi / 4), 0.0, np.cos(np.pi / 4)]  # z axis turned onto x
    parts = [
        ([0.0, 0.0, 0.1, *q_yaw], [{"kind": "box", "size": [0.8, 0.4, 0.2], "pose": [0, 0, 0, 0, 0, 0, 1]}]),
        (
            [2.0, 0.0, 0.1, 0, 0, 0, 1],
            [{"kind": "cylinder", "size": [0.2, 1.0, 0], "pose": [0, 0, 0, *q_lying]}],
        ),
        (
            [0.0, 2.0, 0.1, 0, 0, 0, 1],
            [{"kind": "sphere", "size": [0.3, 0, 0], "pose": [0, 0, 0, 0, 0, 0, 1]}],
        ),
        (
            [2.0, 2.0, 0.5, 0, 0, 0, 1],
            [{"kind": "capsule", "size": [0.25, 0.6, 0], "pose": [0, 0, 0, 0, 0, 0, 1]}],
        ),
    ]
    expected = [0.8 * 0.4, 1.0 * 0.4, np.pi * 0.3**2, np.pi * 0.25**2]
    size, view = 800, 4.0
    scale = size / view
    for k, ((pose, shapes), area) in enumerate(zip(parts, expected)):
        image = top_down(
            np.array([pose]), 0.25, (9.0, 9.0), 0.1, size=size, view=view, centre=(1.0, 1.0), shapes=[shapes]
        )
        drawn = (image == HEAD).all(axis=-1).sum() / scale**2
        perimeter = 2 * np.pi * 0.4 + 2.4  # more than any of these outlines
        assert abs(drawn - area) <= perimeter / scale, (k, drawn, area)
    # Two parts: the head red, the other body grey.
    image = top_down(
        np.array([parts[0][0], parts[1][0]]), 0.25, (9.0, 9.0), 0.1, size=size, view=view,
        centre=(1.0, 1.0), shapes=[parts[0][1], parts[1][1]],
    )  # fmt: skip
    assert (image == HEAD).all(axis=-1).sum() > 0 and (image == BODY).all(axis=-1).sum() > 0


def test_render_of_a_robot_env_uses_its_shapes():
    env = snakesim.SnakeEnv(robot=str(ROBOTS / "wheeled-8.yaml"), render_mode="rgb_array")
    env.reset(seed=0)
    image = env.render()
    assert image.shape == (480, 480, 3) and image.dtype == np.uint8
    cubes = snakesim.SnakeEnv(joints=8, render_mode="rgb_array")
    cubes.reset(seed=0)
    body = lambda img: (img == np.array([70, 70, 80], dtype=np.uint8)).all(axis=-1).sum()  # noqa: E731
    # wheeled-8's links (about 10 cm) are far smaller than the built-in snake's 0.5 m cubes.
    assert 0 < body(image) < body(cubes.render()) / 4


def test_an_agent_trained_on_a_robot_evaluates_and_replays(tmp_path, capsys):
    """The whole path on a robot file: native training, evaluation, and replay to a figure, an
    animation and a Rerun recording, each from the run directory alone (its config names the robot)."""
    import yaml
    from snakesim.cli import app as cli

    config = {
        "joints": 8,  # the robot's movable joints decide; the key is recorded as given
        "timesteps": 1024,
        "n_envs": 2,
        "eval_freq": 1024,
        "checkpoint_freq": 0,
        "eval_episodes": 2,
        "threads": 1,
        "ppo": {"n_steps": 256, "batch_size": 128, "n_epochs": 1},
        "env": {"task": "goal", "robot": str(ROBOTS / "wheeled-8.yaml"), "max_episode_steps": 30},
    }
    path = tmp_path / "wheeled.yaml"
    path.write_text(yaml.safe_dump(config))
    run = tmp_path / "run"
    assert cli.main(["train", "--config", str(path), "--run-dir", str(run), "--no-progress"]) == 0
    assert cli.main(["evaluate", str(run), "--episodes", "2", "--json", str(tmp_path / "e.json")]) == 0
    outs = [tmp_path / "r.png", tmp_path / "r.gif", tmp_path / "r.rrd"]
    code = cli.main(
        [
            "replay",
            str(run),
            "--seconds",
            "1",
            "--out",
            str(outs[0]),
            "--out",
            str(outs[1]),
            "--rrd",
            str(outs[2]),
        ]
    )
    assert code == 0
    for out in outs:
        assert out.is_file() and out.stat().st_size > 1000, out
    printed = capsys.readouterr().out
    assert "wrote" in printed and "recorded episode 1" in printed


def test_cost_of_transport_weighs_the_robot():
    """The evaluation's weight m g (cost of transport's denominator) is the robot's: the sum of its
    URDF links' masses (read here with ElementTree), pybullet's 1 kg for a link without <inertial>."""
    import xml.etree.ElementTree as ET

    from snakesim.agents.evaluation import run_episodes

    urdf = ET.parse(ROBOTS / "wheeled-8.urdf").getroot()
    masses = []
    for link in urdf.findall("link"):
        mass = link.find("inertial/mass")
        masses.append(1.0 if mass is None else float(mass.get("value")))
    kwargs = {"task": "goal", "robot": str(ROBOTS / "wheeled-8.yaml"), "max_episode_steps": 5}
    done = run_episodes(lambda obs: np.zeros((len(obs), 3), dtype=np.float32), kwargs, episodes=2, seed=0)
    assert [e["weight"] for e in done] == pytest.approx([sum(masses) * 9.81] * 2, rel=1e-12)
