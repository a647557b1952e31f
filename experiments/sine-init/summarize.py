"""Issue 48, item 3: the table of docs/experiments.md ("Initialisation by imitation") from the runs of
train_seeds.sh and the evaluations of evaluate_runs.sh: per snake length, with and without init,
the time and timesteps to each seed's first 10/10 periodic evaluation (wall time with evaluations and
the init, from evaluations.csv), its success on the 100 unseen episodes at the end of its run, the
fitted policy's alone, and the controllers' on the same episodes.

    .venv/bin/python experiments/sine-init/summarize.py [runs/sine-init]
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path

from snakesim.sweeps.summary import evaluations


def first_perfect(rows: list[dict[str, float]]) -> tuple[int, float] | None:
    """(timesteps, wall seconds) of the first periodic evaluation at 10/10, if any."""
    first = next((r for r in rows if r["success_rate"] >= 1.0), None)
    return None if first is None else (int(first["timesteps"]), first["wall_time"])


def success(path: Path) -> float | None:
    return json.loads(path.read_text())["success_rate"] if path.is_file() else None


def scalars(run: Path) -> dict[str, list[float]]:
    """The run's TensorBoard scalars by tag, in step order."""
    from tensorboard.backend.event_processing import event_accumulator

    out: dict[str, list[float]] = {}
    for events in sorted((run / "tb").rglob("events.*")):
        acc = event_accumulator.EventAccumulator(str(events), size_guidance={"scalars": 0})
        acc.Reload()
        for tag in acc.Tags()["scalars"]:
            out.setdefault(tag, []).extend(e.value for e in acc.Scalars(tag))
    return out


LEARNERS = {
    "anchor": "init, PPO anchored (paper-init-10.yaml)",
    "init": "init, PPO alone (init.anchor=0)",
    "tuned": "no init (paper-tuned-10)",
}


def fmt(values: list[float], digits: int = 0) -> str:
    if not values:
        return "-"
    median = statistics.median(values)
    return f"{median:,.{digits}f} ({min(values):,.{digits}f}-{max(values):,.{digits}f})"


def main(root: Path) -> None:
    evals = root / "eval"
    groups: dict[tuple[str, int], list[Path]] = {}
    for run in sorted(root.glob("*-*-s*")):
        if not (run / "model.safetensors").is_file():
            continue
        label, joints, _ = run.name.split("-")
        groups.setdefault((label, int(joints)), []).append(run)
    print(
        "| joints | learner | seeds | timesteps per run | run wall time | first 10/10: seeds | "
        "first 10/10: wall time, median (range) | first 10/10: timesteps | 100 unseen episodes, "
        "per seed | fitted policy alone, per seed |"
    )
    print("|---|---|---|---:|---|---|---|---|---|---|")
    for (label, joints), runs in sorted(groups.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        # snakesim's own reader of evaluations.csv, in timestep order (as the sweeps' summaries).
        history = [evaluations(r) for r in runs]
        firsts = [f for f in map(first_perfect, history) if f is not None]
        last = [rows[-1] for rows in history]
        finals = [success(evals / f"{r.name}.json") for r in runs]
        # An anchor run's fitted policy is its init run's, bit for bit (the anchor acts after it).
        alone = [
            success(evals / f"{r.name.replace('anchor-', 'init-', 1)}-alone.json")
            for r in runs
            if label in ("init", "anchor")
        ]
        print(
            f"| {joints} | {LEARNERS[label]} | "
            f"{','.join(r.name.rsplit('-s', 1)[1] for r in runs)} | {int(last[0]['timesteps']):,} | "
            f"{fmt([float(x['wall_time']) for x in last])} s | {len(firsts)} of {len(runs)} | "
            f"{fmt([w for _, w in firsts], 1)} s | {fmt([t for t, _ in firsts])} | "
            f"{', '.join('-' if s is None else f'{s:.2f}' for s in finals)} | "
            f"{', '.join('-' if s is None else f'{s:.2f}' for s in alone) or '-'} |"
        )
    print()
    print("| run | init, s | update, s (mean) | rollout, s (mean) | RSS MiB: first, peak, last |")
    print("|---|---:|---:|---:|---|")
    for _, runs in sorted(groups.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        for run in runs:
            s = scalars(run)
            init = s.get("init/seconds", [float("nan")])[-1]
            rss = s["time/rss_mib"]
            update, rollout = (statistics.mean(s[f"time/{k}_seconds"]) for k in ("update", "rollout"))
            print(
                f"| {run.name} | {init:.1f} | {update:.3f} | {rollout:.3f} | "
                f"{rss[0]:.0f}, {max(rss):.0f}, {rss[-1]:.0f} |"
            )
    print()
    print("| joints | sine | steered_sine |")
    print("|---|---|---|")
    for joints in (5, 10, 20, 30):
        row = [success(evals / f"{c}-{joints}.json") for c in ("sine", "steered_sine")]
        print(f"| {joints} | " + " | ".join("-" if s is None else f"{s:.2f}" for s in row) + " |")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "runs/sine-init"))
