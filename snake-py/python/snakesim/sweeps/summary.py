"""The summary of a sweep: one row per config and grid point, over its seeds: the final success rate and
return (mean and spread), and the timesteps and wall time to the first evaluation with a success rate
of at least ``SUCCESS_THRESHOLD``. Printed as a table and written as ``summary.csv``."""

from __future__ import annotations

import csv
import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from snakesim.files import write_atomically
from snakesim.runs.rundir import EVALUATIONS_FILE, read_evaluations
from snakesim.sweeps.plan import Trial

SUMMARY_FILE = "summary.csv"
#: The success rate a run has learnt the task at (the first evaluation reaching it counts).
SUCCESS_THRESHOLD = 0.9
_TO = f"to_{SUCCESS_THRESHOLD:g}"
#: The derived metric of :func:`with_success_auc`.
SUCCESS_AUC = "success_auc"
COLUMNS = (
    "config",
    "grid",
    "seeds",
    "seeds_evaluated",
    "final_timesteps_mean",
    "final_success_rate_mean",
    "final_success_rate_std",
    "final_success_auc_mean",
    "final_success_auc_std",
    "final_return_mean",
    "final_return_std",
    f"seeds_reaching_{SUCCESS_THRESHOLD:g}",
    f"timesteps_{_TO}_mean",
    f"timesteps_{_TO}_std",
    f"wall_time_{_TO}_mean",
    f"wall_time_{_TO}_std",
)


def evaluations(run_dir: Path) -> list[dict[str, float]]:
    path = run_dir / EVALUATIONS_FILE
    if not path.is_file():
        return []
    try:
        return sorted(read_evaluations(path), key=lambda row: row["timesteps"])
    except (ValueError, OSError):
        return []


def with_success_auc(rows: Sequence[dict[str, float]]) -> list[dict[str, float]]:
    """``rows`` (evaluations in timestep order) with ``success_auc`` added to each: the mean success
    rate of the evaluations up to and including it. With evaluations every ``eval_freq`` timesteps that
    is the area under the success curve over the timesteps trained so far, divided by them: 1 for a run
    that succeeds from its first evaluation on. Unlike the last evaluation's success rate (a handful
    of episodes, which many configurations end at 1), it tells a run that learnt early from one that
    learnt late."""
    out, total = [], 0.0
    for count, row in enumerate(rows, 1):
        total += row["success_rate"]
        out.append({**row, SUCCESS_AUC: total / count})
    return out


def _mean_std(values: Sequence[float]) -> tuple[float | None, float | None]:
    """Mean and sample standard deviation (0 for one value); None for no values."""
    if not values:
        return None, None
    mean = sum(values) / len(values)
    if len(values) == 1:
        return mean, 0.0
    return mean, math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1))


def summarize(out: str | os.PathLike, trials: Sequence[Trial]) -> list[dict[str, Any]]:
    """One row per config and grid point of ``trials`` (in their order), from their evaluations.csv."""
    groups: dict[tuple[str, str], list[Trial]] = {}
    for trial in trials:
        groups.setdefault((trial.config, json.dumps(trial.point)), []).append(trial)
    rows = []
    for (config, point), members in groups.items():
        finals, reached = [], []
        for trial in members:
            history = with_success_auc(evaluations(trial.run_dir(out)))
            if not history:
                continue
            finals.append(history[-1])
            first = next((r for r in history if r["success_rate"] >= SUCCESS_THRESHOLD), None)
            if first is not None:
                reached.append(first)
        row: dict[str, Any] = {
            "config": config,
            "grid": point if point != "{}" else "",
            "seeds": len(members),
            "seeds_evaluated": len(finals),
            "final_timesteps_mean": _mean_std([r["timesteps"] for r in finals])[0],
            f"seeds_reaching_{SUCCESS_THRESHOLD:g}": len(reached),
        }
        for name, key, source in (
            ("final_success_rate", "success_rate", finals),
            ("final_success_auc", SUCCESS_AUC, finals),
            ("final_return", "mean_return", finals),
            (f"timesteps_{_TO}", "timesteps", reached),
            (f"wall_time_{_TO}", "wall_time", reached),
        ):
            row[f"{name}_mean"], row[f"{name}_std"] = _mean_std([r[key] for r in source])
        rows.append(row)
    return rows


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(round(value, 6))
    return str(value)


def write_csv(out: str | os.PathLike, rows: Sequence[dict[str, Any]]) -> Path:
    path = Path(out) / SUMMARY_FILE

    def write(tmp: str) -> None:
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            writer = csv.writer(f)
            writer.writerow(COLUMNS)
            writer.writerows([[_cell(row[c]) for c in COLUMNS] for row in rows])

    write_atomically(path, write)
    return path


def _pm(mean: float | None, std: float | None, digits: int) -> str:
    return "-" if mean is None else f"{mean:,.{digits}f} ± {std:,.{digits}f}"


def format_table(rows: Sequence[dict[str, Any]]) -> str:
    """The summary as an aligned text table (means ± sample standard deviations over seeds)."""
    header = (
        "config / grid point",
        "seeds",
        "timesteps",
        "final success",
        "final return",
        f"success >= {SUCCESS_THRESHOLD:g} after (timesteps; wall s)",
    )
    lines = []
    for row in rows:
        name = row["config"] + ("" if not row["grid"] else " " + _grid_text(row["grid"]))
        count = row[f"seeds_reaching_{SUCCESS_THRESHOLD:g}"]
        if count:
            reached = (
                f"{_pm(row[f'timesteps_{_TO}_mean'], row[f'timesteps_{_TO}_std'], 0)}; "
                f"{_pm(row[f'wall_time_{_TO}_mean'], row[f'wall_time_{_TO}_std'], 1)} "
                f"({count}/{row['seeds_evaluated']} seeds)"
            )
        else:
            reached = f"not reached (0/{row['seeds_evaluated']} seeds)"
        timesteps = row["final_timesteps_mean"]
        lines.append(
            (
                name,
                f"{row['seeds_evaluated']}/{row['seeds']}",
                "-" if timesteps is None else f"{timesteps:,.0f}",
                _pm(row["final_success_rate_mean"], row["final_success_rate_std"], 2),
                _pm(row["final_return_mean"], row["final_return_std"], 1),
                reached,
            )
        )
    widths = [max(len(cells[i]) for cells in [header, *lines]) for i in range(len(header))]
    return "\n".join(
        "  ".join(cell.ljust(width) for cell, width in zip(cells, widths)).rstrip()
        for cells in [header, *lines]
    )


def _grid_text(point_json: str) -> str:
    point = json.loads(point_json)
    return " ".join(f"{k}={v if isinstance(v, str) else json.dumps(v)}" for k, v in point.items())
