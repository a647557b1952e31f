"""Env steps per second: snakesim against the paper's env in pybullet 3.2.7, measured in one run.

    .venv/bin/python scripts/bench_env.py [--joints 5] [--envs 16] [--seconds 5]

Measures, with uniform random actions (episodes truncate after 5000 steps and reset):
  pybullet  alone            the paper's env rebuilt in pybullet (tests/reference/paper_gym_env.py), 1 env
  pybullet  SubprocVecEnv    the same env under Stable-Baselines3's SubprocVecEnv with --envs workers
  snakesim  SnakeEnv         snakesim's Gymnasium env, 1 env, from Python
  snakesim  SnakeVecEnv      snakesim's batched env (Rust threads) with --envs worlds, from Python
and prints each with its ratio to pybullet alone.
"""

import argparse
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "reference"))


def rate_single(env, seconds, rng):
    env.reset(seed=0)
    n = env.action_space.shape[0]
    actions = rng.uniform(-1, 1, (4096, n)).astype(np.float32)
    steps, start = 0, time.perf_counter()
    while True:
        for a in actions[:256]:
            _, _, terminated, truncated, _ = env.step(a)
            steps += 1
            if terminated or truncated:
                env.reset()
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return steps / elapsed
        actions = np.roll(actions, 256, axis=0)


def rate_vec(venv, seconds, rng):
    venv.reset()
    m, n = venv.num_envs, venv.action_space.shape[0]
    actions = rng.uniform(-1, 1, (64, m, n)).astype(np.float32)
    steps, start = 0, time.perf_counter()
    while True:
        for a in actions:
            venv.step(a)  # SB3's VecEnv resets finished envs itself
            steps += m
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return steps / elapsed


def make_paper_env(joints):
    def make():
        from paper_gym_env import PaperSnakeEnv

        return PaperSnakeEnv(joints=joints)

    return make


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--joints", type=int, default=5)
    parser.add_argument("--envs", type=int, default=16)
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args()
    if args.joints < 1 or args.envs < 1 or not args.seconds > 0:
        parser.error("--joints and --envs must be >= 1 and --seconds > 0")

    import snakesim
    from paper_gym_env import PaperSnakeEnv
    from stable_baselines3.common.vec_env import SubprocVecEnv

    rng = np.random.default_rng(0)
    results = {}
    results["pybullet alone (1 env)"] = rate_single(PaperSnakeEnv(joints=args.joints), args.seconds, rng)
    venv = SubprocVecEnv([make_paper_env(args.joints) for _ in range(args.envs)])
    results[f"pybullet SubprocVecEnv ({args.envs} envs)"] = rate_vec(venv, args.seconds, rng)
    venv.close()
    env = snakesim.SnakeEnv(joints=args.joints, preset="snakebot-gym")
    results["snakesim SnakeEnv (1 env)"] = rate_single(env, args.seconds, rng)
    venv = snakesim.SnakeVecEnv(args.envs, joints=args.joints, preset="snakebot-gym")
    results[f"snakesim SnakeVecEnv ({args.envs} envs)"] = rate_vec(venv, args.seconds, rng)
    venv1 = snakesim.SnakeVecEnv(1, joints=args.joints, preset="snakebot-gym")
    results["snakesim SnakeVecEnv (1 env)"] = rate_vec(venv1, args.seconds, rng)

    base = results["pybullet alone (1 env)"]
    sub = results[f"pybullet SubprocVecEnv ({args.envs} envs)"]
    print(f"env steps per second, {args.joints} joints, random actions, {os.cpu_count()} cores")
    print(f"{'':40} {'steps/s':>10} {'vs pybullet alone':>18} {'vs SubprocVecEnv':>17}")
    for name, rate in results.items():
        print(f"{name:40} {rate:10.0f} {rate / base:17.2f}x {rate / sub:16.2f}x")


if __name__ == "__main__":
    main()
