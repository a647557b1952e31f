"""The plot of docs/friction.md: the flat snake's speed against mu_t/mu_f, simulator beside Hu et al.'s
model, for mu_b/mu_f 1 and 1.5.

Its numbers come from the test that checks them (it writes them to target/tmp/hu_model.json):

    SNAKESIM_PYTHON=.venv/bin/python cargo test --release -p snakesim-tests --test hu_model
    .venv/bin/python scripts/friction_figure.py [target/tmp/hu_model.json] [docs/figures/friction-hu.png]
"""

import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else "target/tmp/hu_model.json"
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/figures/friction-hu.png"
    rows = json.load(open(src))
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, rb in zip(axes, (1.0, 1.5)):
        sel = [r for r in rows if r["backward_ratio"] == rb]
        x = [r["transverse_ratio"] for r in sel]
        # Speed towards the head (+x, where the snake starts pointing): a negative one is backwards.
        ax.plot(x, [r["simulated"][0] for r in sel], "o-", label="snakesim (skin friction)")
        ax.plot(x, [r["model_equal"][0] for r in sel], "s--", label="Hu et al.'s model (equal weight)")
        ax.plot(
            x,
            [r["model_weighted"][0] for r in sel],
            "^:",
            label="Hu et al.'s model with Bullet's normal forces",
        )
        ax.axhline(0.0, color="grey", lw=0.5)
        ax.set_xscale("log")
        ax.set_xticks(x, [f"{v:g}" for v in x])
        ax.set_xlabel("mu_t / mu_f")
        ax.set_title(f"mu_b / mu_f = {rb:g}")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("mean forward speed, m/s")
    axes[0].legend(fontsize=8)
    fig.suptitle("flat-17 snake, mu_f = 0.1, sine gait of period 6 s (wave speed 0.142 m/s)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
