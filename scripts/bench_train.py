"""PPO training timesteps/s: snakesim's batched env against the paper's env in pybullet, in one run.

    .venv/bin/python scripts/bench_train.py [--joints 5] [--envs 16] [--rollouts 2] [--torch-threads 1]

Both sides train Stable-Baselines3 PPO with the paper's settings (Table 1: n_steps 4096, batch 64,
10 epochs, lr 3e-4, PPO-small) for the same number of rollouts. snakesim steps its worlds on Rust threads
(SnakeVecEnv); the reference is tests/reference/paper_gym_env.py under SB3's SubprocVecEnv, as the
paper's ppo.py ran it (make_vec_env with 16 envs), and with 2 subprocesses (its best here).

The profile splits each run into rollout collection (env steps + policy inference) and the PPO update
(SB3's gradient steps), from callback timestamps: where the update dominates, a faster env cannot help.
"""

import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "reference"))


def make_paper_env(joints):
    def make():
        from paper_gym_env import PaperSnakeEnv

        return PaperSnakeEnv(joints=joints)

    return make


def profile(venv, rollouts, seed=0):
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback

    class Clock(BaseCallback):
        def __init__(self):
            super().__init__()
            self.marks = []

        def _on_rollout_start(self):
            self.marks.append(("start", time.perf_counter()))

        def _on_rollout_end(self):
            self.marks.append(("end", time.perf_counter()))

        def _on_step(self):
            return True

    n_steps = 4096
    model = PPO("MlpPolicy", venv, n_steps=n_steps, batch_size=64, n_epochs=10, seed=seed, device="cpu")
    clock = Clock()
    total = n_steps * venv.num_envs * rollouts
    start = time.perf_counter()
    model.learn(total, callback=clock)
    wall = time.perf_counter() - start
    times = [t for _, t in clock.marks]
    rollout = sum(times[i + 1] - times[i] for i in range(0, len(times) - 1, 2))
    return {"timesteps": total, "wall": wall, "rollout": rollout, "update": wall - rollout}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--joints", type=int, default=5)
    parser.add_argument("--envs", type=int, default=16)
    parser.add_argument("--rollouts", type=int, default=2)
    parser.add_argument("--torch-threads", type=int, default=1)
    args = parser.parse_args()
    if min(args.joints, args.envs, args.rollouts, args.torch_threads) < 1:
        parser.error("every argument must be >= 1")

    import snakesim
    import torch
    from stable_baselines3.common.vec_env import SubprocVecEnv, VecMonitor

    torch.set_num_threads(args.torch_threads)
    runs = {}
    venv = VecMonitor(snakesim.SnakeVecEnv(args.envs, joints=args.joints, preset="snakebot-gym"))
    runs[f"snakesim SnakeVecEnv ({args.envs} envs)"] = profile(venv, args.rollouts)
    for n in sorted({args.envs, 2}, reverse=True):
        venv = VecMonitor(SubprocVecEnv([make_paper_env(args.joints) for _ in range(n)]))
        # The same number of timesteps as the snakesim run.
        rollouts = max(1, args.rollouts * args.envs // n)
        runs[f"pybullet SubprocVecEnv ({n} envs)"] = profile(venv, rollouts)
        venv.close()

    print(
        f"PPO (SB3, paper's settings) training, {args.joints} joints, {os.cpu_count()} cores, "
        f"torch threads {args.torch_threads}"
    )
    header = f"{'':36} {'timesteps':>10} {'steps/s':>8} {'rollout s':>10} {'update s':>9} {'update %':>9}"
    print(header)
    base = None
    for name, r in runs.items():
        rate = r["timesteps"] / r["wall"]
        print(
            f"{name:36} {r['timesteps']:>10} {rate:>8.0f} {r['rollout']:>10.1f} {r['update']:>9.1f} "
            f"{100 * r['update'] / r['wall']:>8.0f}%"
        )
        base = base or rate
    for name, r in list(runs.items())[1:]:
        print(f"snakesim / {name}: {base / (r['timesteps'] / r['wall']):.2f}x")


if __name__ == "__main__":
    main()
