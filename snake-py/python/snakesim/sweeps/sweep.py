"""Running a sweep's trials (``snakesim sweep``, ``--resume``): plan, connect, run, summarise.

The plan and the folder are :mod:`snakesim.sweeps.plan`; the Ray side is
:mod:`snakesim.sweeps.tune_runner`; the summary :mod:`snakesim.sweeps.summary`.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from snakesim.sweeps import summary, tune_runner
from snakesim.sweeps.plan import (
    DEFAULT_CPUS_PER_TRIAL,
    DEFAULT_MAX_FAILURES,
    SweepError,
    Trial,
    check_cluster_options,
    check_new_out,
    load_configs,
    lock_folder,
    new_manifest,
    parse_grid,
    plan,
    read_manifest,
    start_folder,
    trial_finished,
)


def run_sweep(
    configs: Sequence[str | os.PathLike],
    *,
    out: str | os.PathLike,
    seeds: int,
    grid: Sequence[str] = (),
    sets: Sequence[str] = (),
    address: str | None = None,
    cpus_per_trial: int = DEFAULT_CPUS_PER_TRIAL,
    max_failures: int = DEFAULT_MAX_FAILURES,
    progress: bool | None = None,
) -> int:
    """``snakesim sweep``: plans the trials, writes the plan, runs them; returns the exit status."""
    check_cluster_options(cpus_per_trial, max_failures)
    out_path = check_new_out(out)
    parsed_grid = parse_grid(grid)
    trials = plan(load_configs(configs, sets), parsed_grid, seeds, cpus_per_trial)
    manifest = new_manifest(
        "sweep",
        trials,
        configs=[os.fspath(c) for c in configs],
        grid=parsed_grid,
        seeds=seeds,
        set=list(sets),
        cpus_per_trial=cpus_per_trial,
        max_failures=max_failures,
    )
    # Before writing anything: an unreachable or too small cluster leaves no folder behind.
    with tune_runner.connected(address, cpus_per_trial) as client, start_folder(out_path, manifest):
        print(f"sweep {out_path}: {len(trials)} trials on {client}", flush=True)
        return _run(out_path, trials, trials, cpus_per_trial, max_failures, progress)


def resume_sweep(
    folder: str | os.PathLike,
    *,
    address: str | None = None,
    cpus_per_trial: int | None = None,
    max_failures: int | None = None,
    progress: bool | None = None,
) -> int:
    """``snakesim sweep --resume``: runs the trials of a sweep that have not finished."""
    manifest = read_manifest(folder)
    with lock_folder(Path(folder)):
        return _resume(folder, manifest, address, cpus_per_trial, max_failures, progress)


def _resume(
    folder: str | os.PathLike,
    manifest: Mapping[str, Any],
    address: str | None,
    cpus_per_trial: int | None,
    max_failures: int | None,
    progress: bool | None,
) -> int:
    if manifest["kind"] != "sweep":
        raise SweepError(f"{folder} is a {manifest['kind']}, not a sweep; --resume continues sweeps only")
    cpus = manifest["cpus_per_trial"] if cpus_per_trial is None else cpus_per_trial
    failures = manifest["max_failures"] if max_failures is None else max_failures
    check_cluster_options(cpus, failures)
    out = Path(folder)
    trials = manifest["trials"]
    left = [t for t in trials if not trial_finished(t.run_dir(out))]
    if not left:
        print(f"sweep {out}: all {len(trials)} trials have finished")
        return _run(out, trials, [], cpus, failures, progress)
    with tune_runner.connected(address, cpus) as client:
        print(
            f"sweep {out}: {len(trials) - len(left)} of {len(trials)} trials finished; "
            f"running the other {len(left)} on {client}",
            flush=True,
        )
        return _run(out, trials, left, cpus, failures, progress)


def _run(
    out: Path,
    trials: Sequence[Trial],
    to_run: Sequence[Trial],
    cpus_per_trial: int,
    max_failures: int,
    progress: bool | None,
) -> int:
    outcome = (
        tune_runner.run_trials(out, to_run, cpus_per_trial, max_failures, progress)
        if to_run
        else tune_runner.Outcome()
    )
    rows = summary.summarize(out, trials)
    path = summary.write_csv(out, rows)
    print(summary.format_table(rows))
    print(f"wrote {path}; plot it with: snakesim plot {out} --out {out / 'curves.png'}")
    unfinished = [t.name for t in trials if not trial_finished(t.run_dir(out))]
    for name, error in outcome.errors.items():
        print(f"snakesim sweep: trial {name} failed: {error}", file=sys.stderr)
    if unfinished:
        print(
            f"snakesim sweep: {len(unfinished)} of {len(trials)} trials did not finish; "
            f"continue with: snakesim sweep --resume {out}",
            file=sys.stderr,
        )
        return 130 if outcome.interrupted else 1
    return 0
