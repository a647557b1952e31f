"""``snakesim plot``: learning curves (Figure 3) of runs and sweeps."""

from __future__ import annotations

import argparse
from pathlib import Path

from snakesim.cli.errors import UserError, check_writable
from snakesim.files import write_atomically


def cmd_plot(args: argparse.Namespace) -> int:
    from snakesim.runs.rundir import CONFIG_FILE, EVALUATIONS_FILE
    from snakesim.viewer.plots import plot_runs

    # What it reads: the runs' evaluations and configs (a figure's name cannot be theirs but by a link).
    inputs = [p for run in map(Path, args.runs) for p in (run, run / EVALUATIONS_FILE, run / CONFIG_FILE)]
    out = check_writable(args.out, "--out", inputs)
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UserError(f"cannot write --out {out}: expected a .png, .pdf or .svg file")
    drawn = write_atomically(
        out,
        lambda tmp: plot_runs(
            args.runs,
            tmp,
            title=args.title,
            metric=args.metric,
            group=args.group,
            spread=args.spread,
            x=args.x,
            labels=args.label,
        ),
    )
    print(f"wrote {out}: " + "; ".join(label for label, _ in drawn))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("plot", help="learning curves (Figure 3)")
    p.add_argument(
        "runs", nargs="+", metavar="RUN", help="run directories, evaluations.csv files or sweep folders"
    )
    p.add_argument("--out", "--output", dest="out", required=True, help="the figure (.png, .pdf or .svg)")
    p.add_argument("--title", help="the figure's title")
    p.add_argument(
        "--metric",
        choices=("auto", "mean_return", "success_rate", "mean_steps_to_goal"),
        default="auto",
        help="what to draw (default auto: the return above the success rate, a panel each)",
    )
    p.add_argument(
        "--group",
        choices=("auto", "none", "all"),
        default="auto",
        help="auto: runs differing only in seed are one line (mean, shaded spread)",
    )
    p.add_argument("--spread", choices=("minmax", "std"), default="minmax", help="the shaded band of a group")
    p.add_argument(
        "--x",
        choices=("timesteps", "wall_time"),
        default="timesteps",
        help="the x axis: timesteps, or the wall time of training (default timesteps)",
    )
    p.add_argument(
        "--label",
        action="append",
        metavar="TEXT",
        help="a line's label instead of its config's, once per line in the order they are drawn",
    )
    p.set_defaults(func=cmd_plot)
