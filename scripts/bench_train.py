"""PPO training timesteps/s: the native trainer, Stable-Baselines3 on snakesim, and Stable-Baselines3 on
the paper's pybullet env, measured in one run.

    .venv/bin/python scripts/bench_train.py [--joints 5,10] [--rollouts 2] [--envs 16] [--json out.json]

Every trainer runs the paper's settings (Table 1: n_steps 4096, batch 64, 10 epochs, lr 3e-4, PPO-small,
preset snakebot-gym as the paper's code) for the same number of rollouts:

- native: snakesim's Rust trainer (snake-rl) on 2 threads, evaluations and checkpoints off;
- SB3 + snakesim: SB3 PPO over SnakeVecEnv (Rust threads), 1 torch thread;
- SB3 + pybullet: SB3 PPO over the paper's env (tests/reference/paper_gym_env.py) in SubprocVecEnv, as
  the paper's ppo.py ran it (make_vec_env with 16 envs), and with 2 subprocesses (its best here).

Also measured, in the same run: the batched env's own throughput with uniform random actions, stepped
as the native trainer steps it (no Python in the loop): the ceiling of any trainer. The native trainer's
learning overhead is what it adds to that ceiling: policy inference during rollouts, and the updates.
Each run is split into rollout collection and the PPO update (SB3: from callback timestamps).
Run it on a quiet machine: the figures are only comparable within one run.
"""

import argparse
import json
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "reference"))

N_STEPS = 4096


def make_paper_env(joints):
    def make():
        from paper_gym_env import PaperSnakeEnv

        return PaperSnakeEnv(joints=joints)

    return make


def profile_sb3(venv, rollouts, seed=0):
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.logger import Logger

    class Clock(BaseCallback):
        def __init__(self):
            super().__init__()
            self.marks = []

        def _on_rollout_start(self):
            self.marks.append(time.perf_counter())

        def _on_rollout_end(self):
            self.marks.append(time.perf_counter())

        def _on_step(self):
            return True

    model = PPO("MlpPolicy", venv, n_steps=N_STEPS, batch_size=64, n_epochs=10, seed=seed, device="cpu")
    # A logger with no outputs: without one, SB3 makes an empty $TMPDIR/SB3-<date> folder per run.
    model.set_logger(Logger(folder=None, output_formats=[]))
    clock = Clock()
    total = N_STEPS * venv.num_envs * rollouts
    start = time.perf_counter()
    model.learn(total, callback=clock)
    wall = time.perf_counter() - start
    t = clock.marks
    rollout = sum(t[i + 1] - t[i] for i in range(0, len(t) - 1, 2))
    return {"timesteps": total, "wall": wall, "rollout": rollout, "update": wall - rollout}


def profile_native(joints, envs, rollouts, threads):
    from snakesim import _core

    config = {
        "trainer": "native",
        "joints": joints,
        "preset": "snakebot-gym",
        "n_envs": envs,
        "timesteps": N_STEPS * envs * rollouts,
        "eval_freq": 0,
        "checkpoint_freq": 0,
        "threads": threads,
    }
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        result = _core.train(json.dumps(config), os.path.join(tmp, "run"), False, "{}", object())
        wall = time.perf_counter() - start
    # The final evaluation (which cannot be switched off) is not training: leave it out.
    busy = wall - result["eval_seconds"]
    return {
        "timesteps": result["timesteps"],
        "wall": busy,
        "rollout": result["rollout_seconds"],
        "update": result["update_seconds"],
        "rss_mib": result["rss_mib"],
    }


def bench(joints, envs, rollouts, threads, env_seconds):
    import torch
    from snakesim import _core
    from snakesim.envs.config import env_config
    from snakesim.envs.sb3 import SnakeVecEnv
    from stable_baselines3.common.vec_env import SubprocVecEnv, VecMonitor

    torch.set_num_threads(1)
    runs = {}
    env_rate = _core.env_throughput(
        env_config(joints=joints, preset="snakebot-gym"), envs, threads, env_seconds, 0
    )
    runs["native (snake-rl)"] = profile_native(joints, envs, rollouts, threads)
    venv = VecMonitor(SnakeVecEnv(envs, joints=joints, preset="snakebot-gym"))
    runs[f"SB3 + snakesim SnakeVecEnv({envs})"] = profile_sb3(venv, rollouts)
    for n in sorted({envs, 2}, reverse=True):
        venv = VecMonitor(SubprocVecEnv([make_paper_env(joints) for _ in range(n)]))
        # The same number of timesteps as the other runs.
        runs[f"SB3 + pybullet SubprocVecEnv({n})"] = profile_sb3(venv, max(1, rollouts * envs // n))
        venv.close()
    return env_rate, runs


def report(joints, envs, env_rate, runs):
    print(
        f"\n{joints} joints, paper's settings (PPO-small, n_steps {N_STEPS}, batch 64, 10 epochs), "
        f"{os.cpu_count()} cores"
    )
    print(f"batched env alone, {envs} envs, uniform random actions: {env_rate:,.0f} env steps/s")
    print(f"{'':36} {'timesteps':>10} {'steps/s':>8} {'rollout s':>10} {'update s':>9} {'update %':>9}")
    rates = {}
    for name, r in runs.items():
        rates[name] = r["timesteps"] / r["wall"]
        print(
            f"{name:36} {r['timesteps']:>10} {rates[name]:>8.0f} {r['rollout']:>10.1f} {r['update']:>9.1f} "
            f"{100 * r['update'] / r['wall']:>8.0f}%"
        )
    native = rates["native (snake-rl)"]
    n = runs["native (snake-rl)"]
    overhead = 1 - native / env_rate
    rss = n["rss_mib"]
    print(
        f"native: {native / env_rate:.2f}x the env's own throughput (learning overhead "
        f"{100 * overhead:.0f} % of wall time: inference in rollouts + updates); "
        f"memory {rss[0]:.0f} -> {rss[1]:.0f} MiB"
    )
    for name, rate in rates.items():
        if name != "native (snake-rl)":
            print(f"native / {name}: {native / rate:.2f}x")
    return {"joints": joints, "env_steps_per_s": env_rate, "timesteps_per_s": rates, "runs": runs}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--joints", default="5,10", help="comma-separated joint counts (default 5,10)")
    parser.add_argument("--envs", type=int, default=16)
    parser.add_argument("--rollouts", type=int, default=2)
    parser.add_argument("--threads", type=int, default=2, help="native trainer's threads (default 2)")
    parser.add_argument("--env-seconds", type=float, default=10.0, help="length of the env measurement")
    parser.add_argument("--json", help="also write the figures as JSON")
    args = parser.parse_args()
    try:
        joints = [int(j) for j in args.joints.split(",")]
    except ValueError:
        parser.error(f"--joints expects comma-separated integers, got {args.joints!r}")
    if min([*joints, args.envs, args.rollouts, args.threads]) < 1 or args.env_seconds <= 0:
        parser.error("every count must be >= 1 and --env-seconds positive")
    results = []
    for j in joints:
        env_rate, runs = bench(j, args.envs, args.rollouts, args.threads, args.env_seconds)
        results.append(report(j, args.envs, env_rate, runs))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)
        print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
