"""Learning curves (the paper's Figure 3): evaluation return against timesteps, one line per run or per
group of runs that differ only in their seed (mean line, shaded spread); by default a second panel
below it, the success rate of the same evaluations."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from snakesim.runs import config as runconfig
from snakesim.runs.rundir import EVALUATIONS_FILE, read_evaluations

METRICS = {
    "mean_return": "mean evaluation return",
    "success_rate": "evaluation success rate",
    "mean_steps_to_goal": "mean steps to goal (successful episodes)",
}
TITLES = {
    "mean_return": "Average evaluation return",
    "success_rate": "Evaluation success rate",
    "mean_steps_to_goal": "Mean steps to goal",
}
#: The default, ``auto``: what every run's evaluations log, return above success, one panel each.
AUTO_METRICS = ("mean_return", "success_rate")
AUTO_TITLE = "Evaluation return and success rate"
# Keys that do not change what a run learns: runs equal but for these are seeds of one experiment.
_NOT_THE_EXPERIMENT = ("seed", "eval_seed", "device", "torch_threads", "timesteps", "checkpoint_freq")


class PlotError(ValueError):
    """Runs that cannot be plotted; the message says why."""


#: Longest label of a line (``--label``).
MAX_LABEL = 200

#: The x axes a plot can have, with their labels.
X_AXES = {"timesteps": "timesteps", "wall_time": "wall time of training [s]"}


@dataclasses.dataclass
class Curve:
    name: str
    config: dict[str, Any] | None
    timesteps: np.ndarray
    values: dict[str, np.ndarray]
    wall_time: np.ndarray | None = None
    label: str | None = None  # a sweep's name for the trial's config and grid point


def load_curve(source: str | os.PathLike) -> Curve:
    """A run directory (its evaluations.csv and config.yaml) or an evaluations.csv file."""
    path = Path(source)
    csv_path = path / EVALUATIONS_FILE if path.is_dir() else path
    run_dir = csv_path.parent
    if not csv_path.is_file():
        raise PlotError(
            f"{os.fspath(source)} has no {EVALUATIONS_FILE}" if path.is_dir() else f"{source} does not exist"
        )
    try:
        rows = read_evaluations(csv_path)
    except UnicodeDecodeError:
        raise PlotError(f"{csv_path} is not an evaluations.csv (not UTF-8 text)") from None
    except ValueError as error:  # names the file (a FileError too)
        raise PlotError(str(error)) from None
    except OSError as error:
        raise PlotError(f"cannot read {csv_path}: {error.strerror or error}") from None
    if not rows:
        raise PlotError(f"{csv_path} has no evaluations yet")
    config = None
    if (run_dir / "config.yaml").is_file():
        try:
            config = runconfig.load(run_dir / "config.yaml")
        except runconfig.ConfigError:
            config = None
    rows.sort(key=lambda row: row["timesteps"])
    timesteps = np.array([row["timesteps"] for row in rows])
    values = {metric: np.array([row[metric] for row in rows]) for metric in METRICS}
    wall_time = np.array([row["wall_time"] for row in rows])
    name = (path if path.is_dir() else run_dir).resolve().name
    return Curve(name, config, timesteps, values, wall_time)


def sweep_runs(folder: str | os.PathLike) -> list[tuple[Path, str]]:
    """The evaluated trials of a sweep (or search) folder as (run directory, label), in plan order."""
    from snakesim.sweeps import plan as sweep

    try:
        manifest = sweep.read_manifest(folder)
    except sweep.SweepError as error:
        raise PlotError(str(error)) from None
    if manifest["kind"] == "sweep":
        planned = [(t.run_dir(folder), t.group()) for t in manifest["trials"]]
    else:
        trials = Path(folder) / sweep.TRIALS_DIR
        planned = [(d, d.name) for d in sorted(trials.iterdir())] if trials.is_dir() else []
    runs = [(run, label) for run, label in planned if (run / EVALUATIONS_FILE).is_file()]
    if not runs:
        raise PlotError(f"sweep {os.fspath(folder)} has no evaluated trials yet")
    return runs


def load_curves(sources: Sequence[str | os.PathLike]) -> list[Curve]:
    """Each source's curve; a sweep folder gives its trials', labelled by config and grid point."""
    from snakesim.sweeps.plan import is_sweep

    curves = []
    for source in sources:
        if Path(source).is_dir() and is_sweep(source):
            curves += [dataclasses.replace(load_curve(run), label=label) for run, label in sweep_runs(source)]
        else:
            curves.append(load_curve(source))
    return curves


def _experiment_key(config: Mapping[str, Any] | None, name: str) -> str:
    if config is None:
        return f"run:{name}"
    return runconfig.dump({k: v for k, v in config.items() if k not in _NOT_THE_EXPERIMENT})


def _label(config: Mapping[str, Any] | None, fallback: str) -> str:
    if config is None:
        return fallback
    return f"PPO-{runconfig.arch_label(config['arch'])}, {config['joints']} joints ({config['preset']})"


def group_curves(curves: Sequence[Curve], mode: str = "auto") -> list[tuple[str, list[Curve]]]:
    """``auto``: runs whose configs differ only in seeds form a group; ``none``: one per run; ``all``."""
    if mode == "none":
        return [
            (c.name if c.config is None else f"{_label(c.config, c.name)} [{c.name}]", [c]) for c in curves
        ]
    if mode == "all":
        return [("all runs", list(curves))]
    if mode != "auto":
        raise PlotError(f"unknown group mode {mode!r} (expected auto, none or all)")
    groups: dict[str, list[Curve]] = {}
    for curve in curves:
        groups.setdefault(_experiment_key(curve.config, curve.name), []).append(curve)
    out = []
    labels = [members[0].label or _label(members[0].config, members[0].name) for members in groups.values()]
    for members, label in zip(groups.values(), labels):
        if labels.count(label) > 1:  # same arch/joints/preset but other settings: name the runs
            label = f"{label} [{', '.join(c.name for c in members)}]"
        out.append((label, members))
    return out


def aggregate(curves: Sequence[Curve], metric: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(timesteps, mean, low, high) over runs, on the timesteps all of them cover (interpolated)."""
    if len(curves) == 1:
        c = curves[0]
        v = c.values[metric]
        return c.timesteps, v, v, v
    lo = max(c.timesteps[0] for c in curves)
    hi = min(c.timesteps[-1] for c in curves)
    grid = np.unique(np.concatenate([c.timesteps for c in curves]))
    grid = grid[(grid >= lo) & (grid <= hi)]
    if grid.size == 0:
        raise PlotError("the grouped runs' evaluations do not overlap in timesteps; use --group none")
    stack = np.vstack([np.interp(grid, c.timesteps, c.values[metric]) for c in curves])
    return grid, stack.mean(axis=0), stack.min(axis=0), stack.max(axis=0)


def _draw(ax: Any, label: str, members: Sequence[Curve], metric: str, spread: str) -> tuple[str, int]:
    """One line (a group's mean, its spread shaded) on one panel; returns its label and run count."""
    x, mean, low, high = aggregate(members, metric)
    if len(members) > 1:
        if spread == "std":
            stack = np.vstack([np.interp(x, c.timesteps, c.values[metric]) for c in members])
            low, high = mean - stack.std(axis=0), mean + stack.std(axis=0)
        label = f"{label}, {len(members)} runs"
    (line,) = ax.plot(x, mean, label=label, linewidth=1.6)
    if len(members) > 1:
        ax.fill_between(x, low, high, color=line.get_color(), alpha=0.2, linewidth=0)
    return label, len(members)


def plot_runs(
    sources: Sequence[str | os.PathLike],
    out: str | os.PathLike,
    *,
    title: str | None = None,
    metric: str = "auto",
    group: str = "auto",
    spread: str = "minmax",
    x: str = "timesteps",
    labels: Sequence[str] | None = None,
    dpi: int = 150,
) -> list[tuple[str, int]]:
    """Draws the curves of ``sources`` (run directories, evaluations.csv files, sweep folders) into
    ``out`` (PNG, PDF or SVG by its suffix) against ``x`` (``timesteps`` or ``wall_time``, the run's
    seconds of training); returns (label, runs) per line. ``metric`` ``auto`` draws AUTO_METRICS, a
    panel each, on a shared x axis. ``labels`` name the lines in the order they are drawn (one per
    line) instead of their configs."""
    if x not in X_AXES:
        raise PlotError(f"unknown x axis {x!r} (expected one of: {', '.join(X_AXES)})")
    axis = x
    if metric != "auto" and metric not in METRICS:
        raise PlotError(f"unknown metric {metric!r} (expected auto or one of: {', '.join(METRICS)})")
    metrics = AUTO_METRICS if metric == "auto" else (metric,)
    if spread not in ("minmax", "std"):
        raise PlotError(f"unknown spread {spread!r} (expected minmax or std)")
    curves = load_curves(sources)
    if axis == "wall_time":
        # The same curves drawn against each evaluation's wall time instead of its timesteps.
        curves = [dataclasses.replace(c, timesteps=c.wall_time) for c in curves]
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = group_curves(curves, group)
    if labels is not None:
        if len(labels) != len(groups):
            lines = "; ".join(label for label, _ in groups)
            raise PlotError(f"{len(labels)} labels for {len(groups)} lines ({lines})")
        if any(not label or len(label) > MAX_LABEL for label in labels):
            raise PlotError(f"a label must have 1 to {MAX_LABEL} characters")
        groups = [(label, members) for label, (_, members) in zip(labels, groups)]
    fig, axes = plt.subplots(
        len(metrics), 1, sharex=True, figsize=(7.0, 4.5 + 2.5 * (len(metrics) - 1)), squeeze=False
    )
    drawn = []
    try:
        for panel, (ax,) in zip(metrics, axes):
            drawn = [_draw(ax, label, members, panel, spread) for label, members in groups]
            ax.set_ylabel(METRICS[panel])
            ax.grid(True, alpha=0.3)
            if panel == "success_rate":
                ax.set_ylim(-0.02, 1.02)
        ax = axes[-1][0]
        ax.set_xlabel(X_AXES[axis])
        ax.ticklabel_format(axis="x", style="sci", scilimits=(0, 3))
        default_title = AUTO_TITLE if metric == "auto" else TITLES[metric]
        axes[0][0].set_title(title if title is not None else default_title)
        axes[0][0].legend(fontsize="small", loc="best")
        fig.tight_layout()
        fig.savefig(out, dpi=dpi)
    finally:
        plt.close(fig)
    return drawn
