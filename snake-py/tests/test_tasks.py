"""The peg-field and rough-ground tasks (snakesim/SnakePegs-v0, snakesim/SnakeRough-v0): spaces and
docstring defaults, one layout per seed, robots in the tasks, baselines on them, --env-from, bad input
(docs/tasks.md)."""

from __future__ import annotations

import ctypes
import ctypes.util
import json
from pathlib import Path

import gymnasium
import numpy as np
import pytest
import snakesim
from snakesim import _core
from snakesim.agents.loading import AgentError, env_kwargs_of, load_agent
from snakesim.cli import main as cli_main

ROOT = Path(__file__).resolve().parents[2]
TASKS = {"pegs": "snakesim/SnakePegs-v0", "rough": "snakesim/SnakeRough-v0"}


def layout(env, seed: int) -> str:
    """The episode's world as the core draws it (goal, start and terrain follow from the seed)."""
    _, info = env.reset(seed=seed)
    return json.dumps([info["goal"], info["start"], env.unwrapped._env.world_json()])


@pytest.mark.parametrize("task", TASKS)
def test_spaces_and_docstring_defaults(task):
    env = gymnasium.make(TASKS[task], joints=10)
    assert env.observation_space.shape == (2 + 2 * 10 + 8,)
    assert env.action_space.shape == (3,)
    defaults = json.loads(_core.env_keyword_defaults(task))
    doc = " ".join(type(env.unwrapped).__doc__.split())
    assert env.spec.max_episode_steps == defaults["max_episode_steps"] == 900
    assert "900 env steps" in doc
    d0, d1 = defaults["goal_distribution"]["distance"]
    assert f"distance [{d0:g}, {d1:g}]" in doc
    for key, value in defaults["terrain"][task].items():
        assert f"``{key}`` {value:g}" in doc, key


@pytest.mark.parametrize("task", TASKS)
def test_a_seed_gives_one_layout_and_seeds_differ(task):
    env = gymnasium.make(TASKS[task], joints=5)
    first = layout(env, 3)
    assert layout(env, 4) != first
    assert layout(gymnasium.make(TASKS[task], joints=5), 3) == first


def _ground(world: dict, x: float, y: float) -> float:
    """The drawn heightfield's height at (x, y): bilinear between the four grid points around it."""
    g = world["ground"]
    pts = np.asarray(g["points"]).reshape(g["columns"], g["rows"], 3)
    xs, ys = pts[0, :, 0], pts[:, 0, 1]
    i = int(np.clip(np.searchsorted(xs, x) - 1, 0, len(xs) - 2))
    j = int(np.clip(np.searchsorted(ys, y) - 1, 0, len(ys) - 2))
    fx, fy = (x - xs[i]) / (xs[i + 1] - xs[i]), (y - ys[j]) / (ys[j + 1] - ys[j])
    z = pts[:, :, 2]
    low = z[j, i] * (1 - fx) + z[j, i + 1] * fx
    high = z[j + 1, i] * (1 - fx) + z[j + 1, i + 1] * fx
    return float(low * (1 - fy) + high * fy)


def test_the_terrain_observation_maps_the_drawn_ground_around_the_head():
    joints, side, spacing = 10, 5, 0.75
    import pybullet

    extended = gymnasium.make(TASKS["rough"], joints=joints)
    terrain = gymnasium.make(TASKS["rough"], joints=joints, observation="terrain")
    terrain.unwrapped.set_physics_trace(True)
    dim, n = extended.observation_space.shape[0], 2 + 2 * joints
    assert terrain.observation_space.shape == (dim + 3 + side * side,)

    def check(a, b, goal, world):
        # The paper's values and the wave's phase are the extended observation's, bit for bit.
        np.testing.assert_array_equal(a[:n], b[:n])
        np.testing.assert_array_equal(a[n + 6 :], b[n + 6 : dim])
        x, y = float(b[0]), float(b[1])
        up, grid = b[dim : dim + 3], b[dim + 3 :].reshape(side, side)
        # The head's rotation as pybullet computes it from the head's quaternion: its rows give the
        # world's up in the head frame, its middle column the head's y axis (the body's long axis).
        head = terrain.unwrapped.physics_trace()["poses"][-1][0]
        rotation = np.array(pybullet.getMatrixFromQuaternion(head[3:])).reshape(3, 3)
        np.testing.assert_allclose(up, rotation[2], atol=1e-6)
        # The rolled head frame: the heading of the long axis, left mirrored upside down.
        heading = np.arctan2(-rotation[0, 1], rotation[1, 1])
        mirror = -1.0 if rotation[2, 2] < 0 else 1.0
        s, c = np.sin(heading), np.cos(heading)
        np.testing.assert_allclose(b[n + 2 : n + 4], [s, c], atol=1e-6)
        dx, dy = goal[0] - x, goal[1] - y
        expected_goal = [mirror * (c * dx + s * dy), -s * dx + c * dy]
        np.testing.assert_allclose(b[n : n + 2], expected_goal, atol=1e-4)
        # The middle point is the ground under the head less the head's z; every other point is the
        # ground there, in the rolled head frame (x to the left, y behind), less the same z.
        head_z = _ground(world, x, y) - grid[2, 2]
        for i in range(side):
            for j in range(side):
                hx, hy = mirror * (j - 2) * spacing, (i - 2) * spacing
                expected = _ground(world, x + c * hx - s * hy, y + s * hx + c * hy) - head_z
                assert abs(grid[i, j] - expected) < 1e-4, (i, j, grid[i, j], expected)
        assert np.ptp(grid) > 0.05
        return mirror

    # Seed 5, steered gently: upright after its first step, upside down by its 20th.
    extended.reset(seed=5)
    terrain.reset(seed=5)
    world = json.loads(terrain.unwrapped._env.world_json())  # the episode's ground, drawn at reset
    mirrors = []
    for _ in range(20):
        a, *_ = extended.step(np.array([0.3, 0.0, 0.0], np.float32))
        b, _, _, _, info = terrain.step(np.array([0.3, 0.0, 0.0], np.float32))
        mirrors.append(check(a, b, info["goal"], world))
    assert mirrors[0] == 1.0 and mirrors[-1] == -1.0, mirrors


def test_pegs_lie_between_start_and_goal():
    env = snakesim.SnakePegsEnv(joints=5)
    _, info = env.reset(seed=11)
    world = json.loads(env._env.world_json())
    assert len(world["obstacles"]) > 20
    start, goal = np.array(info["start"][:2]), np.array(info["goal"])
    for peg in world["obstacles"]:
        p = np.array(peg["pose"][:2])
        assert 0.9 < np.linalg.norm(p - start) < np.linalg.norm(goal - start)


@pytest.mark.parametrize("task", TASKS)
@pytest.mark.parametrize("name", ["steer", "gait"])
def test_baselines_run_on_the_tasks_and_on_a_robot(task, name):
    robot = ROOT / "robots" / "yaw-pitch-16.yaml"
    for overrides in (None, {"robot": str(robot)}):
        agent = load_agent(f"baseline:{name}", joints=10, task=task, env_overrides=overrides)
        env = (
            agent.make_env() if hasattr(agent, "make_env") else snakesim.envs.env.make_env(**agent.env_kwargs)
        )
        obs, _ = env.reset(seed=0)
        for _ in range(5):
            obs, *_ = env.step(agent.policy.act(obs)[0])
        assert np.all(np.isfinite(obs))


def test_baseline_on_exactly_a_models_env(tmp_path, capsys):
    from snakesim.cli.args import TASK_IDS

    model = ROOT / "models" / "goal-10.safetensors"
    agent = load_agent(str(model))
    baseline = load_agent("baseline:steer", env_from=str(model))
    assert baseline.env_kwargs == agent.env_kwargs
    assert baseline.kind == "baseline" and baseline.joints == 10
    with pytest.raises(AgentError, match="takes joints and preset"):
        load_agent("baseline:steer", joints=5, env_from=str(model))
    out = tmp_path / "e.json"
    cli_main(["evaluate", "baseline:gait", "--env-from", str(model), "--episodes", "1", "--json", str(out)])
    assert json.loads(out.read_text())["joints"] == 10

    assert set(TASK_IDS) == {"paper", "goal", "swim", *TASKS}
    with pytest.raises(AgentError, match="--env-from"):
        load_agent("baseline:steer", env_from="baseline:gait")
    with pytest.raises(AgentError, match="for baselines"):
        load_agent(str(tmp_path), task="pegs")


def test_a_held_wave_is_the_baseline_with_those_two_actions(tmp_path, capsys):
    """``--hold A,F`` (``load_agent(..., hold=...)``): the same steering as the baseline, the amplitude
    and frequency actions at A and F instead of 0 (the middle of their ranges); bad values, joint-target
    baselines and models refused in one line naming ``--hold``."""
    plain, held = (load_agent("baseline:steer", joints=5, hold=h) for h in (None, (0.5, 1.0)))
    env = snakesim.envs.env.make_env(**plain.env_kwargs)
    obs = np.stack([env.reset(seed=s)[0] for s in range(4)])
    a, b = plain.act(obs), held.act(obs)
    assert np.array_equal(a[:, 0], b[:, 0]) and np.any(a[:, 0] != 0)
    assert np.array_equal(a[:, 1:], np.zeros((4, 2))) and np.array_equal(
        b[:, 1:], np.tile([0.5, 1.0], (4, 1))
    )
    assert held.label == "baseline:steer --hold 0.5,1"
    model = str(ROOT / "models" / "goal-10.safetensors")
    for args, message in [
        (["baseline:steer", "--hold", "1.5,0"], "--hold: amplitude: must be an action in [-1, 1], got 1.5"),
        (["baseline:gait", "--hold", "0,nan"], "--hold: frequency: must be an action in [-1, 1], got NaN"),
        (["baseline:steer", "--hold", "0.5"], "argument --hold: expected AMPLITUDE,FREQUENCY (two numbers)"),
        (["baseline:sine", "--env", "paper", "--hold", "0,0"], "--hold: sine sets joint targets"),
        ([model, "--hold", "0,0"], "--hold is for the gait-action baselines"),
    ]:
        try:
            code = cli_main(["evaluate", *args, "--episodes", "1", "--json", str(tmp_path / "e.json")])
        except SystemExit as exit_:  # argparse's own refusals
            code = exit_.code
        err = capsys.readouterr().err.strip()
        assert code not in (0, None) and len(err.splitlines()) == 1 and message in err, err
        assert not (tmp_path / "e.json").exists()


def test_a_model_runs_in_the_env_it_was_trained_in_after_a_default_changes(tmp_path):
    """A model's keywords resolve with today's defaults; where that differs from the env it recorded
    at training (as after a change to a task's defaults), the recorded values are pinned, so the agent
    and ``--env-from`` baselines still run the trained env."""
    from safetensors import safe_open
    from safetensors.numpy import load_file, save_file

    source = ROOT / "models" / "goal-10.safetensors"
    with safe_open(str(source), "np") as f:
        meta = dict(f.metadata())
    recorded = json.loads(meta["env_config"])
    recorded["max_episode_steps"] = 700  # as if the goal task's 600 had been 700 when it trained
    recorded["goal_distribution"]["distance"] = [4.0, 9.0]
    model = tmp_path / "old-goal-10.safetensors"
    save_file(load_file(str(source)), str(model), metadata={**meta, "env_config": json.dumps(recorded)})

    kwargs = env_kwargs_of(model)
    assert kwargs["max_episode_steps"] == 700 and kwargs["goal_distribution"] == {"distance": [4.0, 9.0]}
    env = snakesim.envs.env.make_env(**kwargs)
    assert env.config["max_episode_steps"] == 700
    assert env.config["goal_distribution"]["distance"] == [4.0, 9.0]
    assert load_agent("baseline:steer", env_from=str(model)).env_kwargs == load_agent(str(model)).env_kwargs

    recorded["goal_radius"] = -1.0
    save_file(load_file(str(source)), str(model), metadata={**meta, "env_config": json.dumps(recorded)})
    with pytest.raises(AgentError, match="as it was trained: with its recorded values, .*goal_radius"):
        load_agent(str(model))


# The first 16 of the 100 episodes of the model cards' tables: `evaluate --seed 900000` seeds its 16
# envs 900000-900015, and each env's first episode is one of the card's.
CARD_SEED, CARD_EPISODES = 900000, 16


def _success(*args: str, tmp_path: Path) -> list[bool]:
    out = tmp_path / "e.json"
    cli_main(
        ["evaluate", *args, "--episodes", str(CARD_EPISODES), "--seed", str(CARD_SEED), "--json", str(out)]
    )
    return [e["success"] for e in json.loads(out.read_text())["per_episode"]]


# The shipped agents of the tasks, by the task their metadata records (models/*.md hold their
# 100-episode tables).
TASK_AGENTS = sorted(
    p.name for p in (ROOT / "models").glob("*.safetensors") if env_kwargs_of(p).get("task") in TASKS
)


@pytest.mark.parametrize("model", TASK_AGENTS)
def test_a_task_agent_reaches_goals_where_steer_fails(model, tmp_path):
    path = str(ROOT / "models" / model)
    agent = _success(path, tmp_path=tmp_path)
    steer = _success("baseline:steer", "--env-from", path, tmp_path=tmp_path)
    # The targets on these 16 of the card's episodes: success at least 0.90 and at least
    # 0.30 above steer's on the same episodes.
    assert len(agent) == len(steer) == CARD_EPISODES
    assert np.mean(agent) >= 0.90, agent
    assert np.mean(agent) - np.mean(steer) >= 0.30, (agent, steer)


def test_the_pegs_and_rough_agents_are_shipped():
    assert {"pegs-10.safetensors", "rough-10.safetensors"} <= set(TASK_AGENTS)


def test_bad_input_is_one_line(capsys):
    with pytest.raises(ValueError, match=r"^terrain\.pegs\.density") as error:
        snakesim.SnakePegsEnv(terrain={"pegs": {"density": 2}})
    assert "\n" not in str(error.value)
    with pytest.raises(ValueError, match=r"^terrain\.rough\.spacing") as error:
        snakesim.SnakeRoughEnv(terrain={"rough": {"spacing": -1}})
    with pytest.raises(ValueError, match="terrain"):
        snakesim.SnakeGoalEnv(terrain={"hills": {}})
    with pytest.raises(SystemExit):
        cli_main(["evaluate", "baseline:steer", "--env", "mountains", "--episodes", "1"])
    assert "unknown task 'mountains'" in capsys.readouterr().err


def _flat_ground_along_the_line(rough: dict, distance: list[float]):
    """For three seeds of the rough task on ground without bumps or hills, with ``rough``'s keys:
    400 points (m from the start) along the straight line from start to goal, and the ground's
    height there (read from the episode's world)."""
    env = snakesim.SnakeRoughEnv(
        terrain={"rough": {"amplitude": 0.0, "hills_amplitude": 0.0, **rough}},
        goal_distribution={"distance": distance},
    )
    for seed in range(3):
        _, info = env.reset(seed=seed)
        world = json.loads(env._env.world_json())
        (x0, y0), (x1, y1) = info["start"][:2], info["goal"]
        t = np.linspace(0, 1, 400)
        line = np.array([_ground(world, x0 + u * (x1 - x0), y0 + u * (y1 - y0)) for u in t])
        yield t * np.hypot(x1 - x0, y1 - y0), line


def test_a_crater_lies_across_the_line_to_the_goal_and_bad_craters_are_one_line():
    """terrain.rough.craters (docs/tasks.md): on ground without bumps or hills, the straight line from
    start to goal dips exactly the crater's depth (its flat bottom) and is flat near both ends (goals
    10-12 m away leave room for the crater between start_clear and goal_clear)."""
    for _, line in _flat_ground_along_the_line({"craters": {"count": 1}}, [10, 12]):
        assert max(line) - min(line) == pytest.approx(2.5, abs=1e-5)
        assert line[0] == pytest.approx(max(line), abs=1e-5) and line[-1] == pytest.approx(
            max(line), abs=1e-5
        )
    with pytest.raises(ValueError, match=r"^terrain\.rough\.craters\.count") as error:
        snakesim.SnakeRoughEnv(terrain={"rough": {"craters": {"count": 99}}})
    assert "\n" not in str(error.value)


def test_a_ridge_lies_across_the_line_to_the_goal_and_bad_ridges_are_one_line():
    """terrain.rough.ridges (docs/tasks.md): on ground without bumps or hills, the straight line from
    start to goal rises exactly the ridge's height (its flat crest) and is flat near both ends (the
    crest at least start_clear 3 m from the start and goal_clear 2 m from the goal, its sides 0.75 m
    wide beyond it)."""
    for along, line in _flat_ground_along_the_line({"ridges": {"count": 1}}, [7, 10]):
        assert max(line) - min(line) == pytest.approx(1.5, abs=1e-5)
        clear = (along < 3.0 - 0.75) | (along > along[-1] - 2.0 + 0.75)
        assert np.ptp(line[clear]) == pytest.approx(0.0, abs=1e-5)
    with pytest.raises(ValueError, match=r"^terrain\.rough\.ridges\.count") as error:
        snakesim.SnakeRoughEnv(terrain={"rough": {"ridges": {"count": 99}}})
    assert "\n" not in str(error.value)

    # Without ridges, progress around them is the straight progress, bit for bit.
    def rewards(progress_around: bool) -> list[float]:
        env = snakesim.SnakeRoughEnv(joints=10, reward={"progress_around_ridges": progress_around})
        env.reset(seed=1)
        return [env.step(np.zeros(3, dtype=np.float32))[1] for _ in range(200)]

    assert rewards(True) == rewards(False)
    with pytest.raises(TypeError, match="^reward.progress_around_ridges: invalid type") as error:
        snakesim.SnakeRoughEnv(reward={"progress_around_ridges": "yes"})
    assert "\n" not in str(error.value)


def test_a_crater_with_terminate_ends_the_episode_over_its_floor():
    """terrain.rough.craters.terminate: the unsteered wave, started facing the goal 12 m ahead across
    flat ground, crawls into the crater and the episode ends (terminated, unsuccessful) on the first
    step whose head is within radius - wall of the crater's centre (read from the episode's world)."""
    flat = {"amplitude": 0.0, "hills_amplitude": 0.0}
    craters = {"count": 1, "offset": 0.0, "terminate": True}
    env = snakesim.SnakeRoughEnv(
        joints=10, terrain={"rough": {**flat, "craters": craters}}, max_episode_steps=600
    )
    # Bullet puts the grid's z = 0 halfway between its lowest and highest sample: the ground is 1.25 m up.
    env.reset(seed=1, options={"start": (0.0, 0.0, 1.75, 0.0), "goal": (0.0, -12.0)})
    world = json.loads(env._env.world_json())
    points = np.asarray(world["ground"]["points"]).reshape(-1, 3)
    floor = points[points[:, 2] < points[:, 2].min() + 1e-6]  # the flat bottom's grid points
    centre, radius = floor[:, :2].mean(axis=0), 3.0 - 0.75  # radius - wall at the defaults
    assert centre[0] == pytest.approx(0.0, abs=0.01) and -8.0 <= centre[1] <= -6.0
    heads = []
    while True:
        _, _, terminated, truncated, info = env.step(np.zeros(3, dtype=np.float32))
        heads.append(np.hypot(*(np.asarray(env.cube_poses()[0][:2]) - centre)))
        if terminated or truncated:
            break
    assert terminated and not info["success"]
    assert heads[-1] < radius and min(heads[:-1]) > radius, heads[-3:]


def test_progress_around_craters_changes_progress_only_where_a_crater_is_in_the_way():
    """reward.progress_around_craters (docs/tasks.md): without craters the rewards are the same bits as
    without the option; with one in the way, the unsteered wave that crawls into it has earned
    metres less progress, while in it, than the straight distance it gained."""

    def rewards(progress_around: bool, craters: dict | None) -> tuple[list[float], float]:
        rough = {"amplitude": 0.0, "hills_amplitude": 0.0, **({"craters": craters} if craters else {})}
        env = snakesim.SnakeRoughEnv(
            joints=10, terrain={"rough": rough}, reward={"progress_around_craters": progress_around}
        )
        z = 1.75 if craters else 0.5  # a crater's ground lies half its depth (2.5 m) up
        _, info = env.reset(seed=1, options={"start": (0.0, 0.0, z, 0.0), "goal": (0.0, -12.0)})
        start = info["distance"]
        out = []
        for _ in range(450):
            _, reward, terminated, truncated, info = env.step(np.zeros(3, dtype=np.float32))
            out.append(reward)
            assert not (terminated or truncated)
        return out, start - info["distance"]

    assert rewards(True, None) == rewards(False, None)
    crater = {"count": 1, "offset": 0.0}
    straight, gained = rewards(False, crater)
    around, _ = rewards(True, crater)
    assert sum(straight) == pytest.approx(gained, abs=1e-4)  # float32 positions
    # Cumulative progress: once in the crater the way out and around is metres longer than the
    # straight line from there, so the progress earned so far falls metres behind the straight one.
    assert min(np.cumsum(around) - np.cumsum(straight)) < -2.0
    with pytest.raises(TypeError, match="^reward.progress_around_craters: invalid type") as error:
        snakesim.SnakeRoughEnv(reward={"progress_around_craters": 1.5})
    assert "\n" not in str(error.value)


def _libm_steer(obs: np.ndarray) -> np.float32:
    """baseline:steer's steering from the goal vector of a 10-joint extended or terrain observation,
    written independently of snakesim: clip(-atan2(gx, -gy), -1, 1) with libm's float32 arctangent
    (numpy's can differ from it in the last bit)."""
    return _steer_of(obs, 22)


def _with_legacy_flag(tmp_path: Path, key: str, value, **env_config) -> Path:
    """models/goal-10 with ``action.KEY`` in its recorded env, as models trained before the
    steering assist left the env record it."""
    from safetensors import safe_open
    from safetensors.numpy import load_file, save_file

    source = ROOT / "models" / "goal-10.safetensors"
    with safe_open(str(source), "np") as f:
        meta = dict(f.metadata())
    recorded = json.loads(meta["env_config"])
    recorded["action"][key] = value
    for name, v in env_config.items():
        recorded[name] = v
    model = tmp_path / f"legacy-{key}.safetensors"
    save_file(load_file(str(source)), str(model), metadata={**meta, "env_config": json.dumps(recorded)})
    return model


def test_a_model_recorded_with_the_envs_former_steer_flags_acts_through_its_assist(tmp_path):
    """A model whose env records ``action.steer_residual`` (before the assist left the env) loads
    with ``steer_assist`` {residual: true}: its env is the plain gait env (which the baselines of
    ``--env-from`` share), and zero corrections drive exactly baseline:steer."""
    model = _with_legacy_flag(tmp_path, "steer_residual", True)
    agent, baseline = load_agent(str(model)), load_agent("baseline:steer", env_from=str(model))
    assert (agent.steer_assist.residual, agent.steer_assist.near_goal) == (True, 0.0)
    assert "steer_residual" not in agent.env_kwargs.get("action", {})
    assert baseline.env_kwargs == agent.env_kwargs and baseline.steer_assist is None

    env = snakesim.envs.env.make_env(**agent.env_kwargs)
    obs, _ = env.reset(seed=3)
    for _ in range(40):
        composed = agent.steer_assist.apply(obs[None, :], np.zeros((1, 3), np.float32))[0]
        np.testing.assert_array_equal(composed, baseline.act(obs)[0])
        assert composed[0] == _libm_steer(obs) and composed.dtype == np.float64
        obs, *_ = env.step(composed)
    # A full correction reaches either end whatever steer asks.
    for correction in (-1.0, 1.0):
        assert agent.steer_assist.apply(obs[None, :], np.array([[correction, 0, 0]]))[0, 0] == correction


def test_the_steer_assist_wrapper_hands_the_last_approach_to_steer_and_bad_uses_are_one_line():
    """``snakesim.wrappers.SteerAssist(env, near_goal=R)``: within R m of the goal, baseline:steer's
    action drives whatever the agent asks (checked against the plain env driven by libm's steer);
    bad values, envs it cannot drive and the env's former keys are one line."""
    from snakesim.wrappers import SteerAssist

    kwargs = {"joints": 10, "action": {"mode": "gait"}, "observation": "extended"}
    kwargs["goal_distribution"] = {"distance": [5.0, 9.0]}  # every goal within the hand-over
    handed = SteerAssist(gymnasium.make("snakesim/SnakeGoal-v0", **kwargs), near_goal=10.0)
    plain = gymnasium.make("snakesim/SnakeGoal-v0", **kwargs)
    assert handed.action_space == plain.action_space
    for seed, action in ((3, [1.0, -1.0, 1.0]), (4, [-1.0, 1.0, -0.5])):
        obs_h, _ = handed.reset(seed=seed)
        obs_p, _ = plain.reset(seed=seed)
        for _ in range(30):
            np.testing.assert_array_equal(obs_h, obs_p)
            assert np.hypot(*obs_p[22:24]) < 10
            obs_h, *_ = handed.step(np.array(action, np.float32))
            obs_p, *_ = plain.step(np.array([_libm_steer(obs_p), 0, 0], np.float32))
        # The action itself would have driven elsewhere.
        handed.reset(seed=seed)
        plain.reset(seed=seed)
        obs_h, *_ = handed.step(np.array(action, np.float32))
        obs_q, *_ = plain.step(np.array(action, np.float32))
        assert not np.array_equal(obs_q, obs_h)

    goal = gymnasium.make("snakesim/SnakeGoal-v0", joints=5)
    for assist, kind, message in (
        ({"near_goal": 11.0}, ValueError, r"steer_assist.near_goal: must be in \[0, 10\] m"),
        ({"near_goal": float("nan")}, ValueError, "steer_assist.near_goal: must be in"),
        ({"near_goal": "near"}, TypeError, "near_goal"),
        ({}, ValueError, "steer_assist: set residual: true, near_goal: METRES or both"),
        ({"residual": "yes"}, TypeError, "residual must be True or False"),
    ):
        with pytest.raises(kind, match=message) as error:
            SteerAssist(goal, **assist)
        assert "\n" not in str(error.value)
    with pytest.raises(ValueError, match="need action mode 'gait' and observation 'extended' or 'terrain'"):
        SteerAssist(
            gymnasium.make("snakesim/SnakeGoal-v0", joints=5, action={"mode": "joints"}), residual=True
        )
    with pytest.raises(ValueError, match=r"action.steer_near_goal: baseline:steer left the env"):
        snakesim.SnakeGoalEnv(joints=10, action={"mode": "gait", "steer_near_goal": 2.0})


def test_a_native_run_with_steer_assist_records_it_and_its_model_acts_through_it(tmp_path, capsys):
    """``steer_assist`` in a run configuration: the native trainer applies it, the model records it
    (metadata ``steer_assist``), and loading the model applies it again; the SB3 trainer refuses it."""
    import yaml
    from safetensors import safe_open

    config = {
        "joints": 4,
        "n_envs": 2,
        "timesteps": 256,
        "eval_freq": 0,
        "eval_episodes": 2,
        "checkpoint_freq": 0,
        "threads": 1,
        "ppo": {"n_steps": 64, "batch_size": 64, "n_epochs": 1},
        "env": {"task": "goal", "max_episode_steps": 50},
        "steer_assist": {"near_goal": 10.0},
    }
    path = tmp_path / "assist.yaml"
    path.write_text(yaml.safe_dump(config))
    run = tmp_path / "run"
    assert cli_main(["train", "--config", str(path), "--run-dir", str(run), "--no-progress"]) == 0
    with safe_open(str(run / "model.safetensors"), "np") as f:
        meta = f.metadata()
    assert json.loads(meta["steer_assist"]) == {"residual": False, "near_goal": 10.0}
    assert "within 10 m of the goal baseline:steer drives" in meta["action"]
    agent = load_agent(str(run / "model.safetensors"))
    assert agent.steer_assist is not None and agent.steer_assist.near_goal == 10.0
    # Every goal of a 50-step episode lies within 10 m of the head, so steer drives every step.
    env = snakesim.envs.env.make_env(**agent.env_kwargs)
    at = env.observation_structure["base_position"] + env.observation_structure["joint_states"]
    obs, _ = env.reset(seed=1)
    for _ in range(20):
        if np.hypot(*obs[at : at + 2]) < 10:
            np.testing.assert_array_equal(agent.act(obs[None, :])[0], [_steer_of(obs, at), 0.0, 0.0])
        obs, *_ = env.step(agent.act(obs[None, :])[0])

    path.write_text(yaml.safe_dump({**config, "trainer": "sb3"}))
    assert cli_main(["train", "--config", str(path), "--run-dir", str(tmp_path / "sb3")]) != 0
    assert "steer_assist: only the native trainer applies it" in capsys.readouterr().err


def _steer_of(obs: np.ndarray, at: int) -> np.float32:
    libm = ctypes.CDLL(ctypes.util.find_library("m"))
    libm.atan2f.restype = ctypes.c_float
    libm.atan2f.argtypes = (ctypes.c_float, ctypes.c_float)
    gx, gy = obs[at : at + 2]
    return np.clip(-np.float32(libm.atan2f(gx, -gy)), -1, 1)


def test_a_larger_height_map_sees_farther_and_bad_maps_are_one_line():
    """``height_map={"side": 9}``: the terrain observation's map is a 9 x 9 grid whose inner 5 x 5 points
    are the default map's; bad grids are one line naming the key."""
    small = snakesim.SnakeRoughEnv(joints=10, observation="terrain")
    large = snakesim.SnakeRoughEnv(joints=10, observation="terrain", height_map={"side": 9})
    assert large.observation_space.shape[0] == small.observation_space.shape[0] - 25 + 81
    assert large.config["height_map"] == {"side": 9, "spacing": 0.75}
    assert "height_map" not in small.config
    obs_s, _ = small.reset(seed=11)
    obs_l, _ = large.reset(seed=11)
    for _ in range(20):
        np.testing.assert_array_equal(obs_s[:-25], obs_l[:-81])
        np.testing.assert_array_equal(obs_s[-25:].reshape(5, 5), obs_l[-81:].reshape(9, 9)[2:7, 2:7])
        obs_s, *_ = small.step(np.array([0.5, 0.0, 0.0], np.float32))
        obs_l, *_ = large.step(np.array([0.5, 0.0, 0.0], np.float32))
    for height_map, kind, message in (
        ({"side": 8}, ValueError, "height_map.side: must be odd, from 1 to 15, got 8"),
        ({"spacing": -1.0}, ValueError, "height_map.spacing: must be in"),
        ({"side": "nine"}, TypeError, "height_map.side: invalid type"),
        ({"reach": 3.0}, ValueError, "height_map.reach: unknown field `reach`"),
    ):
        with pytest.raises(kind, match=message) as error:
            snakesim.SnakeRoughEnv(observation="terrain", height_map=height_map)
        assert "\n" not in str(error.value)
    with pytest.raises(ValueError, match="height_map: needs observation 'terrain'"):
        snakesim.SnakeRoughEnv(height_map={"side": 9})


def test_the_swim_task_its_defaults_and_a_steered_mamba_under_a_drawn_current(tmp_path):
    """``snakesim/SnakeSwim-v0`` (docs/media.md, "Swimming to goals"): the goal task's spaces in the
    built-in pool, the docstring's defaults; baseline:steer swims mamba-10 to its goals under the
    current that snake-py/configs/randomize/current.yaml draws, and each episode reports its current."""
    env = gymnasium.make("snakesim/SnakeSwim-v0", robot=str(ROOT / "robots/mamba-10.yaml"))
    assert env.observation_space.shape == (2 + 2 * 9 + 8,) and env.action_space.shape == (3,)
    defaults = json.loads(_core.env_keyword_defaults("swim"))
    doc = " ".join(type(env.unwrapped).__doc__.split())
    assert env.spec.max_episode_steps == defaults["max_episode_steps"] == 900 and "900 env steps" in doc
    d0, d1 = defaults["goal_distribution"]["distance"]
    assert f"distance [{d0:g}, {d1:g}]" in doc and f"z {defaults['start']['z']:g} m" in doc
    assert defaults["world"]["files"]["pool.yaml"].startswith("media:")
    out = tmp_path / "e.json"
    current = ROOT / "snake-py/configs/randomize/current.yaml"
    cli_main(
        ["evaluate", "baseline:steer", "--env", "swim", "--robot", str(ROOT / "robots/mamba-10.yaml")]
        + ["--randomize", str(current), "--episodes", "2", "--seed", "5", "--json", str(out)]
    )
    result = json.loads(out.read_text())
    assert result["success_rate"] == 1.0, result
    for episode in result["per_episode"]:
        assert 0.0 <= episode["physics"]["current_speed"] <= 0.4
        assert abs(episode["physics"]["current_heading"]) <= np.pi
    with pytest.raises(ValueError, match="randomize.current_speed: needs a world with water"):
        snakesim.SnakeGoalEnv(randomize={"current_speed": [0.0, 0.1]})


def test_the_swim_agent_reaches_its_goals_sooner_than_steer(tmp_path):
    """models/swim-10.md's target on 4 of its card's episodes with the current: both reach every goal,
    the agent in less time (card: 4.36 s against 7.29 s over 100)."""
    model = str(ROOT / "models" / "swim-10.safetensors")
    current = str(ROOT / "snake-py/configs/randomize/current.yaml")
    seconds = {}
    for name, source in (("agent", [model]), ("steer", ["baseline:steer", "--env-from", model])):
        out = tmp_path / f"{name}.json"
        cli_main(
            ["evaluate", *source, "--episodes", "4", "--seed", "900000", "--randomize", current]
            + ["--json", str(out)]
        )
        result = json.loads(out.read_text())
        assert result["success_rate"] == 1.0, (name, result)
        seconds[name] = result["mean_seconds_to_goal"]
    assert seconds["agent"] < 0.8 * seconds["steer"], seconds
