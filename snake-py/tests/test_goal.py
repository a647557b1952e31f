"""The goal-reaching task (snakesim/SnakeGoal-v0): its spaces under Gymnasium's checker, the goals it
draws, its action modes, the paper's env left as it was, bad input, the baselines, evaluation's
metrics and the shipped agents."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest
import snakesim
from gymnasium.utils.env_checker import check_env
from snakesim.agents.loading import env_kwargs_of
from snakesim.envs.env import SnakeEnv, SnakeGoalEnv, make_env

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"


# Gymnasium's checker warns about any infinite Box bound.
@pytest.mark.filterwarnings("ignore:.*observation space m.* value is .*infinity:UserWarning")
@pytest.mark.parametrize("joints", [5, 10, 20])
def test_registered_env_passes_gymnasiums_checker(joints):
    env = gymnasium.make("snakesim/SnakeGoal-v0", joints=joints)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.action_space.shape == (3,)
    assert env.observation_space.shape == (2 + 2 * joints + 8,)
    assert env.spec.max_episode_steps == 600


def test_goals_are_drawn_around_the_start():
    env = SnakeGoalEnv()
    bearings = []
    for seed in range(40):
        _, info = env.reset(seed=seed)
        x, y, _, yaw = info["start"]
        gx, gy = info["goal"]
        distance = math.hypot(gx - x, gy - y)
        assert 5.0 <= distance <= 15.0
        # Bearing from the start heading (ahead is -y rotated by yaw; positive to the left).
        bearings.append(math.atan2(gx - x, -(gy - y)) - yaw)
    wrapped = np.angle(np.exp(1j * np.array(bearings)))
    assert wrapped.min() < -2.5 and wrapped.max() > 2.5, "goals in every direction"
    # The same seed draws the same goal; the reset option still overrides it.
    assert env.reset(seed=3)[1]["goal"] == env.reset(seed=3)[1]["goal"]
    assert env.reset(seed=3, options={"goal": (1.0, 2.0)})[1]["goal"] == (1.0, 2.0)


def test_a_narrow_distribution_puts_the_goal_where_asked():
    env = SnakeEnv(goal_distribution={"distance": [4.0, 4.0], "bearing": [0.0, 0.0]})
    _, info = env.reset(seed=0, options={"start": (1.0, 2.0, 0.5, 0.0)})
    assert info["goal"] == pytest.approx((1.0, -2.0), abs=1e-12), "4 m straight ahead (-y)"
    _, info = env.reset(seed=0, options={"start": (0.0, 0.0, 0.5, math.pi / 2)})
    assert info["goal"] == pytest.approx((4.0, 0.0), abs=1e-12), "heading rotated a quarter turn"


def test_the_paper_env_is_unchanged():
    config = SnakeEnv().config
    assert config["goal_distribution"] is None
    assert config["action"]["mode"] == "joints"
    assert config["reward"]["distance_weight"] == 1.0
    paper, via_task = SnakeEnv(joints=4), make_env("paper", joints=4)
    a, _ = paper.reset(seed=9)
    b, _ = via_task.reset(seed=9)
    for _ in range(50):
        action = np.full(4, 0.3, np.float32)
        oa, ra, *_ = paper.step(action)
        ob, rb, *_ = via_task.step(action)
        assert np.array_equal(oa, ob) and ra == rb


def test_gait_actions_steer_the_snake():
    def sideways(steering: float) -> float:
        """Where the head ends up across its start heading (+x is left of -y, ahead) after 4 s."""
        env = SnakeGoalEnv(goal_distribution=None, goal=(0.0, -1000.0))
        env.reset(seed=0, options={"start": (0.0, 0.0, 0.5, 0.0)})
        for _ in range(120):
            obs, *_ = env.step(np.array([steering, 0.0, 0.0], np.float32))
        return float(obs[0])

    # A negative steering action turns left, as the steering baseline uses it.
    left, straight, right = sideways(-0.5), sideways(0.0), sideways(0.5)
    assert left > straight + 0.5 and right < straight - 0.5, (left, straight, right)


def test_info_reports_work_path_and_displacement():
    env = SnakeGoalEnv()
    env.reset(seed=1)
    for _ in range(60):
        _, _, _, _, info = env.step(np.zeros(3, np.float32))
    assert info["work"] > 0 and math.isfinite(info["work"])
    assert info["path_length"] >= info["displacement"] > 0.5


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"goal_distribution": {"distance": [-1.0, 5.0]}}, "goal_distribution.distance"),
        ({"goal_distribution": {"distance": [9.0, 5.0]}}, "goal_distribution.distance"),
        ({"goal_distribution": {"bearing": [0.0, 7.0]}}, "goal_distribution.bearing"),
        ({"action": {"mode": "fly"}}, "action.mode"),
        ({"action": {"frequency": [0.0, 1.0]}}, "action.frequency"),
        ({"action": {"amplitude": [0.2, 3.0]}}, "action.amplitude"),
        ({"action": {"steering": [-1.0, 0.5]}}, "action.steering"),
    ],
)
def test_bad_task_settings_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        SnakeGoalEnv(**kwargs)


def test_make_env_refuses_an_unknown_task():
    with pytest.raises(ValueError, match="unknown task 'run'"):
        make_env("run")


def _evaluate(*args: str, cwd: Path | None = None) -> dict:
    out = subprocess.run(
        [sys.executable, "-m", "snakesim", "evaluate", *args, "--json", "-"],
        capture_output=True,
        text=True,
        check=True,
        cwd=cwd,
    )
    return json.loads(out.stdout)


def test_the_steering_baseline_reaches_goals_and_reports_the_metrics():
    report = _evaluate("baseline:steer", "--joints", "10", "--episodes", "4", "--seed", "123")
    assert report["success_rate"] == 1.0
    low, high = report["success_rate_ci95"]
    # Wilson's interval for n successes in n: [n / (n + z^2), 1].
    assert low == pytest.approx(4 / (4 + 1.959964**2), rel=1e-12) and high == pytest.approx(1.0, abs=1e-12)
    for key in ("mean_speed", "mean_path_efficiency", "mean_cost_of_transport"):
        assert report[key] > 0, key
    assert 0 < report["mean_path_efficiency"] <= 1


def _flat_goal_task(model: Path) -> bool:
    env = env_kwargs_of(model)
    return env.get("task") == "goal" and "robot" not in env and env.get("world") is None


# The shipped agents of the flat goal task with the cube snake (goal-N, efficient-10; not sand-10, whose
# goal task is in worlds/sand-patch.yaml: models/sand-10.md).
FLAT_GOAL_AGENTS = sorted(p.name for p in MODELS.glob("*.safetensors") if _flat_goal_task(p))


@pytest.mark.parametrize("model", FLAT_GOAL_AGENTS)
def test_shipped_flat_goal_agents_reach_their_goals_and_the_papers(model):
    report = _evaluate(str(MODELS / model), "--episodes", "4", "--seed", "777000")
    assert report["success_rate"] == 1.0, report
    paper = _evaluate(str(MODELS / model), "--episodes", "4", "--seed", "777000", "--goal", "0,-10")
    assert paper["success_rate"] == 1.0, paper


def test_the_goal_agents_are_shipped():
    assert {"goal-5.safetensors", "goal-10.safetensors", "goal-20.safetensors"} <= set(FLAT_GOAL_AGENTS)


def test_the_robot_agent_reaches_its_goals_from_any_directory(tmp_path):
    # Its metadata names robots/yaw-pitch-16.yaml relative to the repository's root, where it was
    # trained; the model finds the file beside its own directory from anywhere (here: a temp dir).
    model = MODELS / "goal-yaw-pitch-16.safetensors"
    report = _evaluate(str(model), "--episodes", "4", "--seed", "777000", cwd=tmp_path)
    assert report["success_rate"] == 1.0, report


def test_the_robust_robot_agent_records_its_physics_and_reaches_its_goals():
    # Trained under randomized physics on the robot with its servos' speed limit
    # (models/robust-yaw-pitch-16.md); here under nominal physics, which its card measures at 1.00.
    model = MODELS / "robust-yaw-pitch-16.safetensors"
    assert set(env_kwargs_of(model)["randomize"]) == {
        "ground_friction",
        "mass_scale",
        "effort_scale",
        "latency_steps",
        "obs_noise",
    }
    nominal = ROOT / "snake-py" / "configs" / "randomize" / "nominal.yaml"
    report = _evaluate(str(model), "--episodes", "4", "--seed", "777000", "--randomize", str(nominal))
    assert report["randomize"] == {} and report["success_rate"] == 1.0, report


def test_a_model_is_shipped():
    assert (MODELS / "goal-5.safetensors").is_file()
    assert snakesim.GOAL_ENV_ID == "snakesim/SnakeGoal-v0"


@pytest.mark.parametrize("joints", [10, 20])
def test_the_paper_agents_solve_the_papers_task(joints):
    # The paper's own env (Snake-v0: fixed goal 10 m ahead, joint-target actions, snakebot-gym masses):
    # paper-10, which neither of the paper's published 10-joint agents ever solved
    # (docs/experiments.md), and paper-20, the steered sine imitated at initialisation (the paper's
    # own proposal, models/paper-20.md).
    model = MODELS / f"paper-{joints}.safetensors"
    env = env_kwargs_of(model)
    assert "task" not in env and env["joints"] == joints and env["preset"] == "snakebot-gym", env
    report = _evaluate(str(model), "--episodes", "4", "--seed", "777000")
    assert report["success_rate"] == 1.0, report


def test_evaluation_lists_the_episodes_in_their_own_order():
    """run_episodes' i-th episode is the same episode whatever the policy: env e of m is seeded with
    seed + e and its later episodes continue its stream, as a Gymnasium env reset once with that seed
    and then without one. Replayed here one by one through gymnasium.make with the steering
    baseline, the episodes' lengths must come out in the listed order (they end in another)."""
    from snakesim.agents.baselines import goal_bearing
    from snakesim.agents.evaluation import run_episodes

    joints, episodes, seed, envs = 5, 20, 77, 16
    structure = gymnasium.make("snakesim/SnakeGoal-v0", joints=joints).unwrapped.observation_structure

    def steer(obs: np.ndarray) -> np.ndarray:
        obs = np.atleast_2d(obs)
        actions = np.zeros((len(obs), 3), dtype=np.float32)
        actions[:, 0] = np.clip(-goal_bearing(obs, structure), -1.0, 1.0)
        return actions

    kwargs = {"task": "goal", "joints": joints}
    listed = [e["steps"] for e in run_episodes(steer, kwargs, episodes, seed)]
    expected = []
    for e in range(envs):
        env = gymnasium.make("snakesim/SnakeGoal-v0", joints=joints)
        obs, _ = env.reset(seed=seed + e)
        for k in range((episodes + e) // envs):
            if k > 0:
                obs, _ = env.reset()
            steps, done = 0, False
            while not done:
                obs, _, terminated, truncated, _ = env.step(steer(obs)[0])
                steps, done = steps + 1, terminated or truncated
            expected.append(steps)
        env.close()
    assert listed == expected
    assert sorted(listed) != listed  # the episodes end in another order than they are listed in
