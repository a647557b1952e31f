"""`baseline:steer` with the wave's amplitude and frequency actions fixed elsewhere than the middle of
their ranges (where `baseline:steer` holds them), on the sand task: the search for the best hand
controller to hold `models/sand-10` against (this folder's README); one pair is `snakesim evaluate
baseline:steer --hold AMPLITUDE,FREQUENCY --env-from SOURCE`. Usage, from the repository root:

    .venv/bin/python experiments/sand-patch/fixed_wave.py SOURCE [EPISODES] [SEED] [AMPLITUDE,FREQUENCY ...]

SOURCE: a model or run directory whose env is used (models/sand-10.safetensors); EPISODES (100) and
SEED (900000) as `snakesim evaluate`'s, so the episodes are the same ones; each AMPLITUDE,FREQUENCY is
a pair of actions in [-1, 1] (default: every pair of -1, 0, 1). Prints one line per pair: success with
its 95 % Wilson interval, mean time to goal, mean speed.
"""

from __future__ import annotations

import sys

from snakesim.agents.baseline_agent import load_baseline
from snakesim.agents.evaluation import run_episodes, summarize
from snakesim.agents.loading import load_agent


def main() -> None:
    source = sys.argv[1]
    episodes = int(sys.argv[2]) if len(sys.argv) > 2 else 100
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else 900000
    pairs = [tuple(float(v) for v in p.split(",")) for p in sys.argv[4:]] or [
        (a, f) for a in (-1.0, 0.0, 1.0) for f in (-1.0, 0.0, 1.0)
    ]
    model = load_agent(source)
    for amplitude, frequency in pairs:
        # `snakesim evaluate baseline:steer --hold AMPLITUDE,FREQUENCY --env-from SOURCE`, pair by pair.
        steer = load_baseline("steer", None, None, None, source=model, hold=(amplitude, frequency))
        r = summarize(run_episodes(steer.act, steer.env_kwargs, episodes, seed))
        low, high = r["success_rate_ci95"]
        seconds = r["mean_seconds_to_goal"]
        time = f"{seconds:.2f} s" if seconds is not None else "-"
        print(
            f"steer, amplitude {amplitude:+g}, frequency {frequency:+g}: success {r['success_rate']:.2f} "
            f"({low:.3f}-{high:.3f}), time to goal {time}, speed {r['mean_speed']:.3f} m/s",
            flush=True,
        )


if __name__ == "__main__":
    main()
