"""Do controllers win the same episodes? Reads ``snakesim evaluate --json`` files of the same episodes
(same env, same ``--seed``) and prints each one's success, how many episodes each pair wins together
beside what independent coins of the same rates would share, the pair's correlation (phi), and how
many controllers won each episode beside the count independence predicts. High overlap means the
episode decides (some are hard); overlap near independence means each run is a draw
(this folder's README).
Usage, from the repository root: .venv/bin/python experiments/ground-or-controller/win_overlap.py
EVAL.json EVAL.json [...]"""

from __future__ import annotations

import itertools
import json
import sys
from pathlib import Path

import numpy as np


def wins(path: str) -> np.ndarray:
    episodes = json.loads(Path(path).read_text())["per_episode"]
    return np.array([bool(e["success"]) for e in episodes])


def independent_counts(rates: list[float]) -> np.ndarray:
    """Probability that k of the controllers win an episode, k = 0..n, if each wins independently."""
    dist = np.array([1.0])
    for p in rates:
        dist = np.convolve(dist, [1.0 - p, p])
    return dist


def main() -> None:
    paths = sys.argv[1:]
    if len(paths) < 2:
        sys.exit("usage: experiments/ground-or-controller/win_overlap.py EVAL.json EVAL.json [...]")
    table = np.array([wins(p) for p in paths])
    if len({len(row) for row in table}) != 1:
        sys.exit("the files hold different numbers of episodes")
    names = [Path(p).stem for p in paths]
    for name, row in zip(names, table):
        print(f"{name}: {row.mean():.2f}")
    for (a, ra), (b, rb) in itertools.combinations(zip(names, table), 2):
        both, expected = np.mean(ra & rb), ra.mean() * rb.mean()
        phi = np.corrcoef(ra, rb)[0, 1] if 0 < ra.mean() < 1 and 0 < rb.mean() < 1 else float("nan")
        print(f"{a} and {b}: both win {both:.2f} (independent: {expected:.2f}), phi {phi:.2f}")
    print_counts(table)


def print_counts(table: np.ndarray) -> None:
    """For a (controllers x episodes) table of wins: the share of episodes won by at least one and by
    all, and how many controllers won each episode beside what independent draws predict."""
    n = len(table)
    per_episode = table.sum(axis=0)
    counts = np.bincount(per_episode, minlength=n + 1)
    expected = independent_counts(list(table.mean(axis=1))) * table.shape[1]
    print(f"won by at least one: {np.mean(per_episode > 0):.2f}, by all: {np.mean(per_episode == n):.2f}")
    print(f"episodes by how many won them (0 to {n}):", " ".join(str(c) for c in counts))
    print("if independent:", " ".join(f"{c:.1f}" for c in expected))


if __name__ == "__main__":
    main()
