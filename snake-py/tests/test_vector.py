"""The batched env through SB3's VecEnv and Gymnasium's vector API."""

from pathlib import Path

import numpy as np
import pytest
import snakesim
from snakesim import SnakeVecEnv, SnakeVectorEnv


def single_env_rollout(seed, actions, **kwargs):
    env = snakesim.SnakeEnv(**kwargs)
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, reward, terminated, truncated, _ = env.step(a)
        out.append((obs, reward, terminated, truncated))
        if terminated or truncated:
            obs, _ = env.reset()
            out.append(obs)
    return out


def test_sb3_vec_env_matches_single_envs_bit_for_bit():
    m, n, steps = 4, 3, 120
    rng = np.random.default_rng(1)
    actions = rng.uniform(-1, 1, (steps, m, n)).astype(np.float32)
    venv = SnakeVecEnv(m, joints=n, max_episode_steps=50)
    venv.seed(100)
    obs = venv.reset()
    for i in range(m):
        single = single_env_rollout(100 + i, actions[:, i], joints=n, max_episode_steps=50)
        assert obs[i].tobytes() == single[0].tobytes()
    stepped = [venv.step(a) for a in actions]
    for i in range(m):
        single = single_env_rollout(100 + i, actions[:, i], joints=n, max_episode_steps=50)
        k = 1
        for obs, rewards, dones, infos in stepped:
            s_obs, s_reward, s_term, s_trunc = single[k]
            assert rewards[i] == np.float32(s_reward)
            assert dones[i] == (s_term or s_trunc)
            if dones[i]:
                assert infos[i]["terminal_observation"].tobytes() == s_obs.tobytes()
                assert infos[i]["TimeLimit.truncated"] == (s_trunc and not s_term)
                k += 1
                assert obs[i].tobytes() == single[k].tobytes(), "the next episode's first observation"
            else:
                assert obs[i].tobytes() == s_obs.tobytes()
            k += 1


def test_sb3_accepts_it():
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    venv = VecMonitor(SnakeVecEnv(2, joints=3, max_episode_steps=64))
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=64, n_epochs=1, seed=0, device="cpu")
    model.learn(256)
    assert model.num_timesteps == 256
    assert len(model.ep_info_buffer) >= 2, "VecMonitor saw the truncated episodes"


def test_gymnasium_vector_env_same_step_autoreset():
    venv = SnakeVectorEnv(3, joints=2, max_episode_steps=5)
    obs, info = venv.reset(seed=7)
    assert obs.shape == (3, 6) and obs.dtype == np.float32
    assert venv.observation_space.shape == (3, 6) and venv.action_space.shape == (3, 2)
    for _ in range(5):
        obs, rewards, terminated, truncated, infos = venv.step(np.zeros((3, 2), np.float32))
    assert truncated.all() and not terminated.any()
    assert infos["_final_obs"].all()
    assert all(o.shape == (6,) for o in infos["final_obs"])
    assert (infos["final_info"]["episode_step"] == 5).all()
    single = snakesim.SnakeEnv(joints=2)
    first, _ = single.reset(seed=7)
    _, _ = single.reset(seed=7)
    assert venv.reset(seed=7)[0][0].tobytes() == first.tobytes()


@pytest.mark.parametrize(
    ("actions", "error", "match"),
    [
        (np.zeros((2, 3), np.float32), ValueError, r"shape \(3, 2\)"),
        (np.zeros(6, np.float32), ValueError, "2-D"),
        (np.zeros((3, 2), np.complex64), TypeError, "float32 or float64"),
        (np.full((3, 2), np.nan), ValueError, "finite"),
    ],
)
def test_bad_batched_actions(actions, error, match):
    venv = SnakeVecEnv(3, joints=2)
    venv.reset()
    with pytest.raises(error, match=match):
        venv.step(actions)


def test_bad_num_envs():
    with pytest.raises(ValueError, match="num_envs"):
        SnakeVecEnv(0, joints=2)
    with pytest.raises(ValueError, match="num_envs"):
        SnakeVectorEnv(-1, joints=2)


@pytest.mark.parametrize(
    "env_id", [snakesim.ENV_ID, snakesim.GOAL_ENV_ID, snakesim.PEGS_ENV_ID, snakesim.ROUGH_ENV_ID]
)
def test_make_vec_gives_the_native_vector_env_as_gymnasium_make_gives_envs(env_id):
    """``gymnasium.make_vec`` (with the vector entry point, and by default) is the native vector env
    with ``gymnasium.make``'s keywords: env i is ``gymnasium.make(ID, **kwargs)`` seeded ``s + i``, bit for
    bit, and episodes end where make's TimeLimit ends them (the task's default, or max_episode_steps)."""
    import gymnasium

    m, joints, steps, limit = 3, 3, 12, 5
    venv = gymnasium.make_vec(env_id, num_envs=m, vectorization_mode="vector_entry_point", joints=joints)
    assert isinstance(venv, SnakeVectorEnv)
    assert isinstance(gymnasium.make_vec(env_id, num_envs=2, joints=joints), SnakeVectorEnv)
    singles = [gymnasium.make(env_id, joints=joints) for _ in range(m)]
    assert venv.single_observation_space.shape == singles[0].observation_space.shape
    assert venv.single_action_space.shape == singles[0].action_space.shape
    obs, _ = venv.reset(seed=40)
    for i, env in enumerate(singles):
        assert obs[i].tobytes() == env.reset(seed=40 + i)[0].tobytes()
    rng = np.random.default_rng(3)
    for _ in range(steps):
        actions = rng.uniform(-1, 1, (m, *venv.single_action_space.shape)).astype(np.float32)
        obs, rewards, terminated, truncated, _ = venv.step(actions)
        for i, env in enumerate(singles):
            s_obs, s_reward, s_term, s_trunc, _ = env.step(actions[i])
            assert (obs[i].tobytes(), rewards[i]) == (
                s_obs.tobytes(),
                np.float64(s_reward).astype(rewards.dtype),
            )
            assert (terminated[i], truncated[i]) == (s_term, s_trunc)
    # A limit of make's: the vector env truncates at the same step.
    short = gymnasium.make_vec(env_id, num_envs=1, joints=joints, max_episode_steps=limit)
    short.reset(seed=1)
    ends = [
        short.step(np.zeros((1, *short.single_action_space.shape), np.float32))[3][0] for _ in range(limit)
    ]
    assert ends == [False] * (limit - 1) + [True]
    with pytest.raises(ValueError, match="task is"):
        gymnasium.make_vec(env_id, num_envs=1, task="nope")


# -- a list of seeds (Gymnasium's), and closing ------------------------------------------------------
def test_reset_takes_a_list_of_seeds_one_per_env():
    """Gymnasium's vector envs take a list of num_envs seeds, env i reset with seeds[i] and None letting
    env i go on with its own stream: the issue's ``reset(seed=[1, 2, 3])`` raised TypeError."""
    venv = SnakeVectorEnv(3, joints=2)
    obs, _ = venv.reset(seed=[1, 2, 3])
    assert obs.tobytes() == venv.reset(seed=1)[0].tobytes(), "[s, s + 1, ...] is seed=s"
    obs, _ = venv.reset(seed=(9, 4, 2**64 - 1))
    for i, seed in enumerate((9, 4, 2**64 - 1)):
        assert obs[i].tobytes() == snakesim.SnakeEnv(joints=2).reset(seed=seed)[0].tobytes()
    # None: env 1 goes on from its last episode (seeded 4), as a single env reset without a seed does.
    obs, _ = venv.reset(seed=np.array([5, 6, 7]))
    single = snakesim.SnakeEnv(joints=2)
    single.reset(seed=6)
    mixed, _ = venv.reset(seed=[11, None, 13])
    assert mixed[1].tobytes() == single.reset()[0].tobytes()
    assert mixed[0].tobytes() == snakesim.SnakeEnv(joints=2).reset(seed=11)[0].tobytes()
    # Steps go on from those episodes, bit for bit as a single env's.
    action = np.full((3, 2), 0.3, np.float32)
    assert venv.step(action)[0][1].tobytes() == single.step(action[1])[0].tobytes()


def test_a_first_reset_with_none_seeds_is_random():
    # None at the first reset draws a fresh seed (as reset() does), not a fixed stream.
    first = [SnakeVectorEnv(2, joints=2).reset(seed=[None, 3])[0] for _ in range(2)]
    assert first[0][0].tobytes() != first[1][0].tobytes()
    assert first[0][1].tobytes() == first[1][1].tobytes()


@pytest.mark.parametrize(
    ("seed", "error", "match"),
    [
        ([1, 2], ValueError, r"a list of seeds holds one per env, 3, got 2"),
        ([1, 2, 3, 4], ValueError, r"one per env, 3, got 4"),
        ([], ValueError, r"one per env, 3, got 0"),
        ([1, -1, 2], ValueError, r"seed\[1\] must be None or an int in \[0, 2\*\*64\), got -1"),
        ([1, 2**64, 2], ValueError, r"seed\[1\] must be .*, got 18446744073709551616"),
        ([1, 2.5, 2], ValueError, r"seed\[1\] must be .*, got 2.5"),
        ([True, 2, 3], ValueError, r"seed\[0\] must be .*, got True"),
        (["1", 2, 3], ValueError, r"seed\[0\] must be .*, got '1'"),
        (-1, ValueError, r"seed must be None or an int in \[0, 2\*\*64\), got -1"),
        (2.0, TypeError, r"seed must be None, an int or a list of 3 seeds \(one per env\), got float"),
        ("123", TypeError, r"got str"),
        ({1, 2, 3}, TypeError, r"got set"),
    ],
)
def test_bad_seeds_are_clear_errors(seed, error, match):
    venv = SnakeVectorEnv(3, joints=2)
    with pytest.raises(error, match=match):
        venv.reset(seed=seed)
    # Nothing was reset: the env still needs its first reset.
    with pytest.raises(Exception, match="reset"):
        venv.step(np.zeros((3, 2), np.float32))


def test_gymnasium_s_own_vector_env_takes_the_same_seeds():
    """The semantics followed: SyncVectorEnv over single envs gives the same observations."""
    import gymnasium

    sync = gymnasium.vector.SyncVectorEnv([lambda: snakesim.SnakeEnv(joints=2) for _ in range(3)])
    ours = SnakeVectorEnv(3, joints=2)
    for seeds in ([4, 8, 15], [16, None, 23]):
        assert ours.reset(seed=seeds)[0].tobytes() == sync.reset(seed=seeds)[0].tobytes()
    with pytest.raises(ValueError, match="num_envs=3"):
        sync.reset(seed=[1, 2])


def _closed_envs():
    import gymnasium

    yield "SnakeVectorEnv", SnakeVectorEnv(2, joints=2), lambda env: env.step(np.zeros((2, 2), np.float32))
    yield "SnakeVecEnv", SnakeVecEnv(2, joints=2), lambda env: env.step(np.zeros((2, 2), np.float32))
    yield "SnakeEnv", snakesim.SnakeEnv(joints=2), lambda env: env.step(np.zeros(2, np.float32))
    made = gymnasium.make(snakesim.GOAL_ENV_ID, joints=2)
    yield "SnakeGoalEnv", made, lambda env: env.step(np.zeros(3, np.float32))


@pytest.mark.parametrize("name", ["SnakeVectorEnv", "SnakeVecEnv", "SnakeEnv", "SnakeGoalEnv"])
def test_a_closed_env_refuses_step_and_reset(name):
    """The issue's case: step after close() still worked. Now step and reset raise Gymnasium's
    ClosedEnvironmentError (its vector envs' convention), and close() twice is fine."""
    from gymnasium.error import ClosedEnvironmentError

    env, step = next((e, s) for n, e, s in _closed_envs() if n == name)
    env.reset()
    step(env)  # works while open
    env.close()
    env.close()
    message = f"this {name} was closed \\(close\\(\\) released its worlds\\): make a new one"
    with pytest.raises(ClosedEnvironmentError, match=message):
        step(env)
    with pytest.raises(ClosedEnvironmentError, match=message):
        env.reset()
    env.close()


def test_the_make_vec_example_of_docs_guide_md_runs(capsys):
    """docs/guide.md's make_vec example, as written: its infos are what the page says."""
    import contextlib
    import io

    page = (Path(__file__).resolve().parents[2] / "docs" / "guide.md").read_text()
    marker = "<!-- make_vec example: snake-py/tests/test_vector.py runs it -->\n```python\n"
    code = page.split(marker, 1)[1].split("```", 1)[0]
    printed = io.StringIO()
    scope: dict = {}
    with contextlib.redirect_stdout(printed):
        exec(compile(code, "guide.md", "exec"), scope)
    assert printed.getvalue().count("\n") >= 1, "no episode ended in the example"
    envs, infos = scope["envs"], scope["infos"]
    assert scope["structure"] == envs.observation_structure
    assert sum(scope["structure"].values()) == scope["obs"].shape[1]
    assert set(infos) <= {"final_obs", "_final_obs", "final_info", "_final_info"}
