"""A run directory: its file names, its evaluations, its checkpoints and its writer lock.

A run lives in one directory (both trainers; the native one writes ``.safetensors`` where SB3 writes
``.zip``)::

    config.yaml          the resolved configuration (seeds included); reloads equal
    versions.json        snakesim, the trainer's packages and Python versions
    evaluations.csv      timesteps, mean_return, std_return, success_rate, mean_steps_to_goal, wall_time
    tb/PPO_1/            TensorBoard logs
    checkpoints/         model_<T>_steps.zip or .safetensors (+ vecnormalize_<T>_steps.pkl, ...)
    model.zip            SB3's final model (also written on Ctrl-C), vecnormalize.pkl with normalize: true
    model.safetensors    the native trainer's final model
    writer.lock          who writes the run now: one writer per run directory (snakesim._core.lock_run_dir)

Every file is written whole, through a temporary file renamed into place, or appended a row at a time,
so readers (evaluate, plot, replay) need no lock and never see half a file.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from snakesim import _core
from snakesim.files import open_regular

EVAL_FIELDS = ("timesteps", "mean_return", "std_return", "success_rate", "mean_steps_to_goal", "wall_time")
EVALUATIONS_FILE = "evaluations.csv"
VERSIONS_FILE = "versions.json"
TB_DIR = "tb"
TB_NAME = "PPO"


MODEL_FILE = "model.zip"
NATIVE_MODEL_FILE = "model.safetensors"
VECNORMALIZE_FILE = "vecnormalize.pkl"
#: ``snakesim export``'s statistics: ``NAME_vecnormalize.pkl`` beside ``NAME.zip``.
EXPORTED_STATISTICS_SUFFIX = "_vecnormalize.pkl"
CONFIG_FILE = "config.yaml"
CHECKPOINT_DIR = "checkpoints"
_CHECKPOINT = re.compile(r"^model_(\d+)_steps\.zip$")
_NATIVE_CHECKPOINT = re.compile(r"^model_(\d+)_steps\.safetensors$")


class RunDirError(ValueError):
    """A run directory that cannot be used as asked (exists, missing, nothing to resume, ...)."""


def lock_run_dir(run_dir: Path, *, new_run: bool):
    """The run directory's writer lock (``snakesim._core.WriterLock``), held until released: a new run's
    folder must be absent or empty (it is created), a resumed run's must exist; RunDirError naming the
    process that writes it when another one does."""
    try:
        return _core.lock_run_dir(os.fspath(run_dir), new_run)
    except ValueError as error:
        raise RunDirError(str(error)) from None


def default_run_dir(config: Mapping[str, Any]) -> Path:
    """``runs/ppo-ARCH-JOINTS-PRESET-seedSEED``, as ``snake-cli train`` (snake-rl decides)."""
    return Path(_core.default_run_dir(json.dumps(dict(config))))


def csv_value(value: Any) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "nan"
    return repr(value) if isinstance(value, float) else str(value)


def read_evaluations(path: str | os.PathLike) -> list[dict[str, float]]:
    """Rows of an evaluations.csv as floats (``nan`` where no episode reached the goal); ValueError
    naming the file (and the line and column) for anything else, a non-finite number included."""
    with open_regular(path, "csv_bytes") as raw, io.TextIOWrapper(raw, encoding="utf-8", newline="") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames is None or not set(EVAL_FIELDS) <= set(reader.fieldnames):
            raise ValueError(
                f"{os.fspath(path)} is not an evaluations.csv (expected columns {', '.join(EVAL_FIELDS)})"
            )
        rows = []
        for row in reader:
            try:
                values = {key: float(row[key]) for key in EVAL_FIELDS}
            except (TypeError, ValueError):
                raise ValueError(bad_row(path, reader.line_num, row.values())) from None
            for key, value in values.items():
                # Only the steps to goal may be nan: no episode of that evaluation reached it.
                if not math.isfinite(value) and not (key == "mean_steps_to_goal" and math.isnan(value)):
                    raise ValueError(
                        f"{os.fspath(path)}: line {reader.line_num}, column {key}: {row[key][:20]!r} is not "
                        "a finite number"
                    )
            rows.append(values)
        return rows


def bad_row(path: str | os.PathLike, line: int, cells) -> str:
    text = ",".join(str(c) for c in cells if c is not None)
    return f"{os.fspath(path)}: line {line} is not an evaluation row: {text[:80]!r}"


def checkpoints(run_dir: str | os.PathLike, native: bool = False) -> list[tuple[int, Path]]:
    """The run's checkpoints as (timesteps, path), oldest first: SB3's zips, or the native trainer's
    safetensors files with ``native``."""
    folder = Path(run_dir) / CHECKPOINT_DIR
    if not folder.is_dir():
        return []
    pattern = _NATIVE_CHECKPOINT if native else _CHECKPOINT
    found = []
    for path in folder.iterdir():
        match = pattern.match(path.name)
        if match:
            found.append((int(match.group(1)), path))
    return sorted(found)


def checkpoint_paths(run_dir: str | os.PathLike, timesteps: int) -> tuple[Path, Path]:
    folder = Path(run_dir) / CHECKPOINT_DIR
    return folder / f"model_{timesteps}_steps.zip", folder / f"vecnormalize_{timesteps}_steps.pkl"
