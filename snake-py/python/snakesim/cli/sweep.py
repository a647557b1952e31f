"""``snakesim sweep``: every config x grid point x seed as a Ray Tune trial (docs/sweeps.md)."""

from __future__ import annotations

import argparse
from typing import Any

from snakesim.cli.args import int_at_least, threads
from snakesim.sweeps import plan as sweep
from snakesim.sweeps.plan import DEFAULT_CPUS_PER_TRIAL, DEFAULT_MAX_FAILURES, SweepError


def cluster_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a config key for every trial (repeatable)",
    )
    p.add_argument(
        "--address",
        metavar="HOST:PORT",
        help="a running Ray cluster (what `ray start --head` prints; default: a local Ray for this command; "
        f"an unreachable one is an error within {sweep.CONNECT_TIMEOUT_S:g} s)",
    )
    p.add_argument(
        "--cpus-per-trial",
        dest="cpus_per_trial",
        metavar="C",
        type=threads,
        help=f"CPUs Ray reserves per trial, also its threads unless the config sets them "
        f"(default {sweep.DEFAULT_CPUS_PER_TRIAL})",
    )
    p.add_argument(
        "--max-failures",
        dest="max_failures",
        metavar="F",
        type=int_at_least(0, sweep.MAX_FAILURES),
        help="retries of a trial whose worker dies, from its last checkpoint "
        f"(default {sweep.DEFAULT_MAX_FAILURES})",
    )
    p.add_argument(
        "--progress",
        dest="progress",
        action="store_true",
        default=None,
        help="show trial counts and the time left on stderr (the default: a bar on a terminal, otherwise "
        "a line whenever the counts change)",
    )
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no trial counts")


def cmd_sweep(args: Any) -> int:
    from snakesim.sweeps.sweep import resume_sweep, run_sweep

    """``snakesim sweep`` from its parsed arguments (see snakesim.cli)."""
    cluster = {"address": args.address, "progress": args.progress}
    if args.resume is not None:
        if args.configs or args.out or args.seeds is not None or args.grid or args.set:
            raise SweepError(
                "--resume continues a sweep as planned: give no configs, --out, --seeds, --grid or --set"
            )
        return resume_sweep(
            args.resume, cpus_per_trial=args.cpus_per_trial, max_failures=args.max_failures, **cluster
        )
    if not args.configs or args.out is None:
        raise SweepError("a new sweep needs CONFIG.yaml ... and --out (or --resume SWEEP to continue one)")
    return run_sweep(
        args.configs,
        out=args.out,
        seeds=1 if args.seeds is None else args.seeds,
        grid=args.grid,
        sets=args.set,
        cpus_per_trial=args.cpus_per_trial or DEFAULT_CPUS_PER_TRIAL,
        max_failures=DEFAULT_MAX_FAILURES if args.max_failures is None else args.max_failures,
        **cluster,
    )


def add_parser(sub) -> None:
    p = sub.add_parser(
        "sweep",
        help="train every config x grid point x seed on a Ray cluster",
        description="Every (config, grid point, seed) is one run directory under --out, trained as a Ray "
        "Tune trial. See docs/sweeps.md.",
    )
    p.add_argument(
        "configs", nargs="*", metavar="CONFIG.yaml", help="run configurations (see snake-py/configs/)"
    )
    p.add_argument(
        "--out", "--output", dest="out", metavar="SWEEPS/NAME", help="the sweep's folder (new, or empty)"
    )
    p.add_argument(
        "--seeds",
        metavar="K",
        type=int_at_least(1, sweep.MAX_SEEDS),
        help="seeds per config and grid point: the config's seed and the next K-1 (default 1)",
    )
    p.add_argument(
        "--grid",
        action="append",
        default=[],
        metavar="KEY=V1,V2,...",
        help="values of a config key to train each config with (repeatable: every combination)",
    )
    p.add_argument(
        "--resume", metavar="SWEEPS/NAME", help="finish an interrupted sweep: run its unfinished trials"
    )
    cluster_options(p)
    p.set_defaults(func=cmd_sweep)
