"""Skin friction (issue 27) through the Python envs and run configurations: ``snake={"skin_friction": ...}``
reaches the core, changes the motion as Hu et al.'s law says it should, and bad values are one-line
ValueErrors."""

import re

import numpy as np
import pytest
import snakesim
from snakesim import SnakeVecEnv, SnakeVectorEnv
from snakesim.runs import config as runconfig

SKIN = {"forward": 0.05, "backward": 0.05, "transverse": 5.0}
ISOTROPIC = {"forward": 5.0, "backward": 5.0, "transverse": 5.0}
# The built-in 10-joint snake on pybullet snake.py's wave (the residual mode with zero residuals), its
# goal too far away to end the episode.
GAIT = dict(joints=10, action={"mode": "residual"}, physics_steps_per_env_step=2, goal=(0.0, -1000.0))
START = (0.0, 0.0, 0.25, 0.0)


def crawl(steps=1200, **kwargs):
    """The gait for ``steps`` env steps from a fixed start; the last observation and info."""
    env = snakesim.SnakeEnv(**GAIT, **kwargs)
    obs, info = env.reset(seed=0, options={"start": START})
    action = np.zeros(env.action_space.shape, np.float32)
    for _ in range(steps):
        obs, _, terminated, truncated, info = env.step(action)
        assert np.all(np.isfinite(obs))
        assert not (terminated or truncated), "the episode should not end"
    return env, obs, info


def test_skin_friction_steps_and_changes_the_motion():
    plain, plain_obs, _ = crawl()
    skin, skin_obs, skin_info = crawl(snake={"skin_friction": SKIN})
    _, _, iso_info = crawl(snake={"skin_friction": ISOTROPIC})
    assert "skin_friction" not in plain.config["snake"]
    assert skin.config["snake"]["skin_friction"] == SKIN
    assert plain_obs.tobytes() != skin_obs.tobytes()
    # Hu et al. (2009): a snake whose skin is isotropic makes no net progress by lateral undulation;
    # skin that slides 100 times more easily along the body than across it carries it metres. Over
    # 10 s (the head swings about a metre sideways, so shorter runs blur the difference).
    assert skin_info["displacement"] > 5.0, skin_info
    assert iso_info["displacement"] < 0.1 * skin_info["displacement"], (iso_info, skin_info)


def test_vector_envs_and_run_configs_carry_it(tmp_path):
    kwargs = dict(GAIT, snake={"skin_friction": SKIN}, max_episode_steps=40)
    venv = SnakeVecEnv(2, **kwargs)
    venv.seed(7)
    first = venv.reset()
    action = np.zeros((2, 10), np.float32)
    for _ in range(20):
        obs, _, _, _ = venv.step(action)
    for i in range(2):
        env = snakesim.SnakeEnv(**kwargs)
        single, _ = env.reset(seed=7 + i)
        assert first[i].tobytes() == single.tobytes()
        for _ in range(20):
            single, *_ = env.step(action[i])
        assert obs[i].tobytes() == single.tobytes()
    gym_obs, _ = SnakeVectorEnv(2, **kwargs).reset(seed=7)
    assert gym_obs.tobytes() == first.tobytes()

    # A run's env table (trainers, evaluate, replay and the saved config.yaml build their envs from it).
    config = runconfig.validate({"joints": 10, "env": {"snake": {"skin_friction": {**SKIN, "axis": "-y"}}}})
    path = tmp_path / "config.yaml"
    runconfig.save(config, path)
    assert "skin_friction" in path.read_text()
    loaded = runconfig.load(path)
    assert loaded == config
    env = snakesim.SnakeEnv(**runconfig.env_kwargs(loaded))
    assert env.config["snake"]["skin_friction"] == {**SKIN, "axis": "-y"}


@pytest.mark.parametrize(
    "skin, match",
    [
        (
            {**SKIN, "forward": -1.0},
            r"^snake\.skin_friction\.forward: must be finite and in \[0, 10\], got -1\.0$",
        ),
        ({**SKIN, "backward": float("nan")}, r"^snake\.skin_friction\.backward: must be finite"),
        (
            {**SKIN, "transverse": 11.0},
            r"^snake\.skin_friction\.transverse: must be finite and in \[0, 10\], got 11\.0$",
        ),
        ([0.1, 0.2], "invalid length 2"),
        ({"forward": 0.1, "backward": 0.2}, "missing field `transverse`"),
        ({**SKIN, "axis": "up"}, "axis: unknown variant `up`"),
        ({**SKIN, "grip": 1.0}, "unknown field `grip`"),
    ],
)
def test_bad_skin_friction_is_a_one_line_value_error(skin, match):
    with pytest.raises(ValueError, match=r"^snake\.skin_friction") as caught:
        snakesim.SnakeEnv(joints=5, snake={"skin_friction": skin})
    message = str(caught.value)
    assert "\n" not in message
    assert re.search(match, message), message
    # (A NaN is caught before the Rust side, by the check of the whole run config: "config.env....".)
    with pytest.raises(runconfig.ConfigError, match=r"^(config\.)?env\.snake\.skin_friction") as caught:
        runconfig.validate({"env": {"snake": {"skin_friction": skin}}})
    assert "\n" not in str(caught.value)
