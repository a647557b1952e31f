#!/usr/bin/env python3
"""Mamba's swimming trends for docs/media.md (issue 60): mamba-10's forward speed in worlds/pool.yaml
against each of Kelasidi et al.'s gait parameters (alpha, omega, delta), one at a time around this
project's base gaits (lateral undulation alpha 30 deg, eel-like motion alpha 50 deg; both omega 70
deg/s, delta 40 deg), beside the two measured speeds (Kelasidi et al. 2016, IEEE RAM 23(1), p. 54).

    .venv/bin/python scripts/water_figures.py [--out docs/figures/water-mamba-trends.png]

Prints the table docs/media.md quotes and writes the figure (about 20 s of simulation on one core).
"""

from __future__ import annotations

import argparse

from snakesim.validation.water import mamba

BASE = {"lateral": (30.0, 70.0, 40.0), "eel": (50.0, 70.0, 40.0)}
MEASURED = {"lateral": 0.1288, "eel": 0.0894}
SWEEPS = {
    "alpha": [10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
    "omega": [30.0, 50.0, 70.0, 90.0, 120.0, 150.0],
    "delta": [10.0, 20.0, 40.0, 60.0, 80.0],
}


def speed(pattern: str, alpha: float, omega: float, delta: float) -> float:
    return mamba(pattern, alpha, omega, delta, MEASURED[pattern]).simulated


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/figures/water-mamba-trends.png")
    args = parser.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(10, 3.2), sharey=True)
    for ax, (key, values) in zip(axes, SWEEPS.items(), strict=True):
        for pattern, colour in (("lateral", "tab:blue"), ("eel", "tab:orange")):
            a, w, d = BASE[pattern]
            speeds = []
            for v in values:
                p = {"alpha": a, "omega": w, "delta": d, key: v}
                speeds.append(speed(pattern, p["alpha"], p["omega"], p["delta"]))
                shown = f"alpha {p['alpha']:5.1f} omega {p['omega']:6.1f} delta {p['delta']:5.1f}"
                print(f"{pattern:8s} {shown}  {speeds[-1]:.4f} m/s")
            ax.plot(values, speeds, "o-", color=colour, label=f"{pattern} (simulated)")
            base = {"alpha": a, "omega": w, "delta": d}[key]
            ax.plot(
                [base], [MEASURED[pattern]], "*", color=colour, markersize=12, label=f"{pattern} measured"
            )
        ax.set_xlabel(f"{key} ({'deg/s' if key == 'omega' else 'deg'})")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("forward speed (m/s)")
    axes[0].legend(fontsize=7)
    fig.suptitle(
        "mamba-10 in water: one parameter at a time (stars: Mamba measured, at parameters not retrieved)",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(args.out, dpi=80)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
