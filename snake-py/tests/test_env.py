"""snakesim.SnakeEnv as Gymnasium and Stable-Baselines3 see it."""

import pickle

import gymnasium
import numpy as np
import pytest
import snakesim
from gymnasium.utils.env_checker import check_env as gym_check_env


def make(**kwargs):
    return gymnasium.make("snakesim/Snake-v0", **kwargs)


def test_registered_and_configurable():
    env = make(joints=5)
    assert env.action_space.shape == (5,)
    assert env.observation_space.shape == (12,)
    assert env.observation_space.dtype == np.float32
    env = make(
        joints=3,
        preset="snakebot-gym",
        goal=(2.0, 1.0),
        goal_radius=0.5,
        max_episode_steps=10,
        physics_steps_per_env_step=2,
        action_scale=0.5,
        observation="extended",
        start={"x": [0, 0], "y": [0, 0], "yaw": [0.1, 0.1]},
        reward={"progress_weight": 1.0},
        snake={"motor_force": 5.0},
    )
    assert env.observation_space.shape == (2 + 6 + 6,)
    config = env.unwrapped.config
    assert config["snake"]["link_mass"] == 1.0 and config["snake"]["motor_force"] == 5.0
    assert config["goal"] == [2.0, 1.0] and config["physics_steps_per_env_step"] == 2


# The observation is genuinely unbounded (positions, unwrapped joint angles), as the paper declares it;
# Gymnasium's checker warns about any infinite Box bound.
@pytest.mark.filterwarnings("ignore:.*observation space m.* value is .*infinity:UserWarning")
def test_gymnasium_env_checker():
    gym_check_env(make(joints=4, render_mode="rgb_array").unwrapped, skip_render_check=False)


def test_stable_baselines3_env_checker():
    from stable_baselines3.common.env_checker import check_env

    check_env(snakesim.SnakeEnv(joints=4), warn=True)


def rollout(env, seed, steps=200):
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(0)
    out = [obs]
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(
            rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        )
        out.append(np.append(obs, np.float32(reward)))
        if terminated or truncated:
            break
    return out


def test_seeding_reproduces_episodes_exactly():
    a, b = make(joints=5), make(joints=5)
    for x, y in zip(rollout(a, 7), rollout(b, 7)):
        assert x.tobytes() == y.tobytes()
    first = rollout(a, 8)[0]
    assert first.tobytes() != rollout(b, 7)[0].tobytes(), "another seed, another start"
    # Unseeded resets continue the seeded stream, so a sequence of episodes is reproducible too.
    a.reset(seed=3)
    b.reset(seed=3)
    assert a.reset()[0].tobytes() == b.reset()[0].tobytes()


def test_start_and_goal_options():
    env = make(joints=5)
    obs, info = env.reset(options={"start": (1.0, 2.0, 0.25, 0.0), "goal": (1.0, 1.5)})
    assert info["start"] == (1.0, 2.0, 0.25, 0.0)
    assert abs(obs[0] - 1.0) < 1e-3 and abs(obs[1] - 2.0) < 1e-3
    _, reward, terminated, _, info = env.step(np.zeros(5, np.float32))
    assert terminated and reward == 100.0 and info["success"], "the head starts within 1 m of the goal"
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"speed": 1})


@pytest.mark.parametrize("factory", [snakesim.SnakeEnv, make])
def test_truncation_at_max_episode_steps(factory):
    # Through gymnasium.make, max_episode_steps becomes Gymnasium's TimeLimit; directly, the env's own.
    env = factory(joints=2, max_episode_steps=3)
    env.reset(seed=0)
    flags = [env.step(np.zeros(2, np.float32))[2:4] for _ in range(3)]
    assert flags == [(False, False), (False, False), (False, True)]


def test_step_after_the_end_needs_reset():
    env = snakesim.SnakeEnv(joints=2, max_episode_steps=1)
    env.reset(seed=0)
    env.step(np.zeros(2, np.float32))
    with pytest.raises(ValueError, match="reset"):
        env.step(np.zeros(2, np.float32))


def test_reward_terms_are_reported():
    env = make(joints=5, reward={"progress_weight": 2.0, "smoothness_weight": 0.1, "energy_weight": 0.01})
    env.reset(seed=1)
    _, reward, _, _, info = env.step(np.full(5, 0.5, np.float32))
    total = info["reward_goal"] + info["reward_progress"] + info["reward_smoothness"] + info["reward_energy"]
    assert reward == pytest.approx(total, abs=1e-12)
    assert info["reward_smoothness"] == pytest.approx(-0.1 * 5 * 0.25)
    assert info["reward_goal"] == -info["distance"]


def test_pickles():
    env = snakesim.SnakeEnv(joints=3, preset="snakebot-gym", goal=(1.0, -4.0))
    copy = pickle.loads(pickle.dumps(env))
    assert copy.config == env.config
    assert rollout(copy, 5, 50)[-1].tobytes() == rollout(env, 5, 50)[-1].tobytes()


def test_render_rgb_array_shows_snake_and_goal():
    env = make(joints=5, render_mode="rgb_array", goal=(0.0, -3.0))
    env.reset(seed=0)
    for _ in range(20):
        env.step(env.action_space.sample())
    image = env.render()
    assert image.shape == (480, 480, 3) and image.dtype == np.uint8
    red = (image[..., 0] == 200) & (image[..., 1] == 40)
    green = (image[..., 0] == 40) & (image[..., 1] == 160)
    assert red.sum() > 50, "the head cube is drawn"
    assert green.sum() > 50, "the goal ring is drawn"


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"joints": 0}, ValueError, r"^joints: must be in \[1, 128\], got 0"),
        ({"joints": 2.5}, TypeError, "^joints: invalid type: floating point `2.5`"),
        ({"preset": "heavy"}, ValueError, "^preset: unknown variant `heavy`"),
        ({"observation": "pixels"}, ValueError, "^observation: unknown variant `pixels`"),
        ({"goal": (float("nan"), 0.0)}, ValueError, r"^goal\[0\]: must be finite"),
        ({"goal_radius": -1.0}, ValueError, r"^goal_radius: must be in \[0, 10000\]"),
        ({"max_episode_steps": 0}, ValueError, r"^max_episode_steps: must be in \[1, 10000000\]"),
        ({"snake": {"wings": 2}}, ValueError, "^snake.wings: unknown field `wings`"),
        ({"start": {"x": [1.0, 0.0]}}, ValueError, r"^start.x: must have low <= high"),
        ({"reward": {"bonus": 1}}, ValueError, "^reward.bonus: unknown field `bonus`"),
        # Values are not coerced: the wrong type is a TypeError naming the keyword (issue 12, item 7).
        ({"max_episode_steps": 2.9}, TypeError, "^max_episode_steps: invalid type: floating point `2.9`"),
        ({"action_scale": "2"}, TypeError, '^action_scale: invalid type: string "2"'),
        ({"goal": (True, False)}, TypeError, r"^goal\[0\]: invalid type: boolean `true`"),
        (
            {"reward": {"progress_weight": "a"}},
            TypeError,
            '^reward.progress_weight: invalid type: string "a"',
        ),
        ({"render_mode": "human"}, ValueError, "render_mode"),
    ],
)
def test_bad_arguments_raise_clear_errors(kwargs, error, match):
    with pytest.raises(error, match=match):
        snakesim.SnakeEnv(**kwargs)


def test_unknown_keyword_is_rejected():
    with pytest.raises(TypeError, match="speed"):
        make(joints=5, speed=3)


@pytest.mark.parametrize(
    ("action", "error", "match"),
    [
        (np.zeros(4, np.float32), ValueError, "5"),
        (np.zeros((1, 5), np.float32), ValueError, "1-D"),
        (np.full(5, np.nan, np.float32), ValueError, "finite"),
        (np.zeros(5, np.complex64), TypeError, "float32 or float64"),
        ("left", ValueError, "1-D"),
    ],
)
def test_bad_actions_raise_clear_errors(action, error, match):
    env = snakesim.SnakeEnv(joints=5)
    env.reset(seed=0)
    with pytest.raises(error, match=match):
        env.step(action)
    env.step(np.zeros(5, np.float32))  # the env is still usable


def test_bad_reset_options():
    env = snakesim.SnakeEnv(joints=5)
    with pytest.raises(ValueError, match="finite"):
        env.reset(options={"start": (0.0, float("inf"), 0.5, 0.0)})
    with pytest.raises(ValueError, match="finite"):
        env.reset(options={"goal": (float("nan"), 1.0)})
    with pytest.raises(ValueError, match="step.*reset|reset"):
        snakesim.SnakeEnv(joints=5).step(np.zeros(5, np.float32))


def test_actions_are_clipped():
    a, b = snakesim.SnakeEnv(joints=3), snakesim.SnakeEnv(joints=3)
    a.reset(seed=4)
    b.reset(seed=4)
    for _ in range(30):
        oa = a.step(np.full(3, 7.0, np.float32))[0]
        ob = b.step(np.full(3, 1.0, np.float32))[0]
    assert oa.tobytes() == ob.tobytes()


def test_env_signature_defaults_are_the_rust_defaults():
    # SnakeEnv spells its keywords out for help() and IDEs; their defaults must be snake-rl's, the one
    # source of them, read here straight from the compiled core.
    import inspect
    import json

    from snakesim import _core

    tables = ("start", "reward", "action", "snake")  # None means the task's defaults
    for cls in (snakesim.SnakeEnv, snakesim.SnakeGoalEnv):
        rust = json.loads(_core.env_keyword_defaults(cls.task))
        params = inspect.signature(cls.__init__).parameters
        assert set(params) - {"self", "render_mode"} == set(rust) | set(tables)
        for name, value in rust.items():
            if name in tables:
                continue
            default = params[name].default
            assert (list(default) if isinstance(default, tuple) else default) == value, (cls, name)
        for name in tables:
            assert params[name].default is None
