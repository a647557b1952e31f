"""``snakesim search``: hyperparameters by Optuna and ASHA on Ray (docs/sweeps.md)."""

from __future__ import annotations

from typing import Any

from snakesim.cli.args import int_at_least
from snakesim.cli.sweep import cluster_options
from snakesim.sweeps import plan as sweep


def cmd_search(args: Any) -> int:
    from snakesim.sweeps.search import search

    return search(
        args.config,
        space=args.space,
        out=args.out,
        trials=args.trials,
        metric=args.metric,
        sets=args.set,
        address=args.address,
        cpus_per_trial=args.cpus_per_trial or sweep.DEFAULT_CPUS_PER_TRIAL,
        max_failures=sweep.DEFAULT_MAX_FAILURES if args.max_failures is None else args.max_failures,
        progress=args.progress,
    )


def add_parser(sub) -> None:
    p = sub.add_parser(
        "search",
        help="search hyperparameters with Optuna and ASHA on a Ray cluster",
        description="Optuna chooses each trial's values from --space, ASHA stops trials that trail; the best "
        "trial's config is written as OUT/best.yaml. See docs/sweeps.md.",
    )
    p.add_argument("config", metavar="CONFIG.yaml", help="the run configuration the space varies")
    p.add_argument("--space", required=True, metavar="SPACE.yaml", help="keys and their distributions")
    p.add_argument(
        "--trials", required=True, metavar="T", type=int_at_least(1, sweep.MAX_TRIALS), help="trials to run"
    )
    from snakesim.sweeps.search import METRICS

    p.add_argument(
        "--metric",
        choices=METRICS,
        default=METRICS[0],
        help="maximised: the last evaluation's success_rate or mean_return, or success_auc (the mean success "
        "rate over the run's evaluations, which rewards learning early)",
    )
    p.add_argument(
        "--out",
        "--output",
        dest="out",
        required=True,
        metavar="SWEEPS/NAME",
        help="the search's folder (new, or empty)",
    )
    cluster_options(p)
    p.set_defaults(func=cmd_search)
