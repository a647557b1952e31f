"""Sweeps: every (config, grid point, seed) is one training run, run as a Ray Tune trial.

A sweep lives in one folder (``--out``)::

    sweep.json          the plan: what kind of sweep, its configs, grid, seeds and trials (the marker
                        that the folder is a sweep; ``--resume`` reads it)
    trials/NAME/        one ordinary run directory per trial (the layout of ``snakesim train``), plus
                        sessions.jsonl: one line per training session of the trial (a retried or
                        resumed trial has several)
    tune/session-N/     Ray Tune's records of the N-th ``snakesim sweep`` session (results, errors)
    summary.csv         one row per config and grid point (see :mod:`snakesim.sweeps.summary`)

A trial's seeds are its config's ``seed`` and the next ``K - 1``; ``--set`` applies to every config
and the grid's values replace theirs. Everything is checked before Ray is started. Running the trials
is :mod:`snakesim.sweeps.sweep`; the Ray side (the trainable, progress, connecting) is
:mod:`snakesim.sweeps.tune_runner`; searches are :mod:`snakesim.sweeps.search`.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from snakesim import _core
from snakesim.files import FileError, read_text, rewrite_atomically
from snakesim.limits import LIMITS
from snakesim.runs import config as runconfig
from snakesim.runs import rundir

MANIFEST_FILE = "sweep.json"
MANIFEST_FORMAT = "snakesim-sweep"
MANIFEST_VERSION = 1
TRIALS_DIR = "trials"
TUNE_DIR = "tune"
#: Most seeds per config and grid point, and most trials in one sweep.
MAX_SEEDS = LIMITS["sweep_seeds"]
MAX_TRIALS = LIMITS["sweep_trials"]
#: Most values of one ``--grid`` key.
MAX_GRID_VALUES = LIMITS["grid_values"]
#: Most retries of a failed trial (``--max-failures``), and the default.
MAX_FAILURES = LIMITS["trial_failures"]
DEFAULT_MAX_FAILURES = 2
#: CPUs Ray reserves for each trial (``--cpus-per-trial``) unless told otherwise.
DEFAULT_CPUS_PER_TRIAL = 1
#: Seconds to reach a cluster given by --address before giving up with an error.
CONNECT_TIMEOUT_S = 30.0
#: Seconds a retried trial waits for the run directory's earlier writer (a worker Ray gave up on that
#: is still ending) before it fails, leaving the folder to that writer.
TRIAL_LOCK_WAIT_S = 60.0
#: Longest trial folder name (before a number that keeps names apart).
_MAX_NAME = LIMITS["trial_name"]


class SweepError(ValueError):
    """A sweep that cannot be run as asked; the message says why (one line)."""


@dataclasses.dataclass(frozen=True)
class Trial:
    """One training run of a sweep: its folder name, config, grid point and seed, and the layered
    configuration overrides that make it (resolved by :func:`snakesim.runs.config.resolve`)."""

    name: str
    config: str
    point: dict[str, Any]
    seed: int
    overrides: dict[str, Any]

    def run_dir(self, sweep_dir: str | os.PathLike) -> Path:
        return Path(sweep_dir).resolve() / TRIALS_DIR / self.name

    def group(self) -> str:
        """The row of the summary (and the line of the plot) the trial belongs to."""
        return group_name(self.config, self.point)


def group_name(config: str, point: Mapping[str, Any]) -> str:
    return ", ".join([config, *(f"{key}={_text(value)}" for key, value in point.items())])


def _text(value: Any) -> str:
    return value if isinstance(value, str) else json.dumps(value)


# -- the grid -------------------------------------------------------------------------------------
def _split_values(text: str) -> list[str]:
    """``1,2,[3, 4]`` -> ``["1", "2", "[3, 4]"]``: commas inside brackets or quotes do not split."""
    values, depth, quote, start = [], 0, "", 0
    for i, char in enumerate(text):
        if quote:
            quote = "" if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char in "[{":
            depth += 1
        elif char in "]}":
            depth -= 1
        elif char == "," and depth == 0:
            values.append(text[start:i])
            start = i + 1
    values.append(text[start:])
    return [v.strip() for v in values]


def parse_grid(items: Sequence[str]) -> dict[str, list[Any]]:
    """``["ppo.learning_rate=1e-4,3e-4", "n_envs=8,16"]`` -> ``{key: [values]}``; every value is
    parsed as YAML (as ``--set`` parses it)."""
    grid: dict[str, list[Any]] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise SweepError(f"--grid {item!r}: expected KEY=V1,V2,...")
        if key in grid:
            raise SweepError(f"--grid {key} is given twice; list all its values in one --grid")
        if key in ("seed", "eval_seed"):
            raise SweepError(f"--grid {key}: seeds are set by --seeds, not by the grid")
        texts = _split_values(text)
        if not text.strip() or any(not t for t in texts):
            raise SweepError(f"--grid {key}: the grid is empty (expected {key}=V1,V2,...)")
        if len(texts) > MAX_GRID_VALUES:
            raise SweepError(f"--grid {key}: {len(texts)} values, at most {MAX_GRID_VALUES}")
        values = []
        for t in texts:
            parsed = runconfig.parse_set([f"{key}={t}"])
            for part in key.split("."):
                parsed = parsed[part]
            values.append(parsed)
        if len({json.dumps(v, sort_keys=True) for v in values}) < len(values):
            raise SweepError(f"--grid {key}: a value is listed twice")
        grid[key] = values
    return grid


def grid_points(grid: Mapping[str, Sequence[Any]]) -> list[dict[str, Any]]:
    """Every combination of the grid's values (one empty point for no grid), first key slowest."""
    points: list[dict[str, Any]] = [{}]
    for key, values in grid.items():
        points = [{**point, key: value} for point in points for value in values]
    return points


def nested(key: str, value: Any) -> dict[str, Any]:
    """``nested("ppo.n_steps", 64)`` -> ``{"ppo": {"n_steps": 64}}``."""
    out: Any = value
    for part in reversed(key.split(".")):
        out = {part: out}
    return out


# -- planning -------------------------------------------------------------------------------------
def load_configs(paths: Sequence[str | os.PathLike], sets: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Each YAML file (checked) with ``--set`` over it, by the file's name without .yaml."""
    if not paths:
        raise SweepError("no configs given (expected one or more CONFIG.yaml)")
    extra = runconfig.parse_set(list(sets))
    configs: dict[str, dict[str, Any]] = {}
    for path in paths:
        name = Path(path).name.removesuffix(".yaml").removesuffix(".yml")
        if name in configs:
            raise SweepError(f"two configs are named {name}; give each config file its own name")
        data = runconfig.load_yaml(path)
        try:
            runconfig.validate(runconfig.merge(data, extra))
        except runconfig.ConfigError as error:
            raise runconfig.ConfigError(f"{os.fspath(path)}: {error}") from None
        configs[name] = runconfig.merge(data, extra)
    return configs


def _folder_name(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._=+-]+", "_", text).strip("_")[:_MAX_NAME] or "trial"


def plan(
    configs: Mapping[str, Mapping[str, Any]],
    grid: Mapping[str, Sequence[Any]],
    seeds: int,
    cpus_per_trial: int = DEFAULT_CPUS_PER_TRIAL,
) -> list[Trial]:
    """The trials of every config x grid point x seed, each configuration checked. A trial's threads
    (native) or torch threads (SB3) are its CPUs unless its configuration sets them."""
    if not 1 <= seeds <= MAX_SEEDS:
        raise SweepError(f"--seeds must be in [1, {MAX_SEEDS}], got {seeds}")
    points = grid_points(grid)
    count = len(configs) * len(points) * seeds
    if count > MAX_TRIALS:
        raise SweepError(f"the sweep has {count:,} trials, at most {MAX_TRIALS:,}")
    trials: list[Trial] = []
    names: set[str] = set()
    for config_name, config in configs.items():
        for point in points:
            layers = [config, *(nested(key, value) for key, value in point.items())]
            try:
                base = runconfig.validate(runconfig.merge(*layers))
            except runconfig.ConfigError as error:
                raise runconfig.ConfigError(f"{group_name(config_name, point)}: {error}") from None
            threads_key = "threads" if base["trainer"] == "native" else "torch_threads"
            if base[threads_key] is None:
                layers.append({threads_key: cpus_per_trial})
            for seed in range(base["seed"], base["seed"] + seeds):
                overrides = runconfig.merge(*layers, {"seed": seed})
                try:
                    runconfig.resolve(overrides)
                except runconfig.ConfigError as error:
                    raise runconfig.ConfigError(
                        f"{group_name(config_name, point)}, seed {seed}: {error}"
                    ) from None
                label = "_".join([config_name, *(f"{k}={_text(v)}" for k, v in point.items())])
                name = f"{_folder_name(label)}_seed{seed}"
                while name in names:  # names that differ only in characters a folder name drops
                    name = f"{name}_{len(trials)}"
                names.add(name)
                trials.append(Trial(name, config_name, dict(point), seed, overrides))
    return trials


# -- the sweep folder -----------------------------------------------------------------------------
def check_new_out(out: str | os.PathLike) -> Path:
    """A folder for a new sweep: absent or empty, its parent existing."""
    out = Path(out)
    if out.exists():
        if (out / MANIFEST_FILE).is_file():
            raise SweepError(
                f"{out} is already a sweep; continue it with --resume {out}, or choose another --out"
            )
        if not out.is_dir():
            raise SweepError(f"--out {out} exists and is not a folder")
        if any(p.name != _core.LOCK_FILE for p in out.iterdir()):
            raise SweepError(f"--out {out} exists, is not empty and is not a sweep; choose another --out")
    elif not out.parent.is_dir():
        raise SweepError(f"--out {out}: folder {out.parent} does not exist")
    return out


def lock_folder(out: Path, wait_seconds: float = 0.0, what: str = "folder"):
    """The writer lock of a sweep's (or a search's) folder, or a trial's run directory, held until
    released: one writer per folder. SweepError naming the process that writes it when another one
    does."""
    try:
        return _core.lock_folder(os.fspath(out), what, wait_seconds)
    except ValueError as error:
        raise SweepError(str(error)) from None


def start_folder(out: Path, manifest: Mapping[str, Any]):
    """Creates a new sweep's (or search's) folder, locks it and writes its plan; returns the lock."""
    out.mkdir(exist_ok=True)
    lock = lock_folder(out)
    check_new_out(out)  # again, under the lock: another sweep may have started there meanwhile
    write_manifest(out, manifest)
    return lock


def write_manifest(out: Path, manifest: Mapping[str, Any]) -> None:
    out.mkdir(exist_ok=True)
    text = json.dumps(manifest, indent=2) + "\n"
    rewrite_atomically(out / MANIFEST_FILE, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def new_manifest(kind: str, trials: Sequence[Trial], **fields: Any) -> dict[str, Any]:
    return {
        "format": MANIFEST_FORMAT,
        "version": MANIFEST_VERSION,
        "kind": kind,
        "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        **fields,
        "trials": [dataclasses.asdict(trial) for trial in trials],
    }


def read_manifest(folder: str | os.PathLike) -> dict[str, Any]:
    """The plan of a sweep folder; SweepError when the folder is not a sweep."""
    path = Path(folder) / MANIFEST_FILE
    if not Path(folder).is_dir():
        raise SweepError(f"{folder} is not a sweep folder (no such folder)")
    if not path.is_file():
        raise SweepError(f"{folder} is not a sweep folder (no {MANIFEST_FILE})")
    try:
        manifest = json.loads(read_text(path, "config_bytes"))
        if manifest.get("format") != MANIFEST_FORMAT:
            raise ValueError(f"format is not {MANIFEST_FORMAT}")
        if manifest.get("version") != MANIFEST_VERSION:
            raise ValueError(f"version {manifest.get('version')!r}, this snakesim reads {MANIFEST_VERSION}")
        manifest["trials"] = [Trial(**trial) for trial in manifest["trials"]]
    except FileError as error:
        raise SweepError(str(error)) from None
    except (ValueError, TypeError, KeyError, AttributeError, OSError, RecursionError) as error:
        raise SweepError(f"{path} is not a readable sweep plan: {error}") from None
    return manifest


def is_sweep(folder: str | os.PathLike) -> bool:
    return (Path(folder) / MANIFEST_FILE).is_file()


def trial_finished(run_dir: Path) -> bool:
    """Whether a trial's run has trained all its timesteps (its latest checkpoint is at or past them)."""
    config_path = run_dir / rundir.CONFIG_FILE
    if not config_path.is_file():
        return False
    try:
        config = runconfig.load(config_path)
    except runconfig.ConfigError:
        return False
    found = rundir.checkpoints(run_dir, native=config["trainer"] == "native")
    return bool(found) and found[-1][0] >= config["timesteps"]


def next_session(out: Path) -> str:
    """The Tune experiment name of this session: session-1, session-2, ..."""
    folder = out / TUNE_DIR
    taken = [p.name for p in folder.iterdir()] if folder.is_dir() else []
    number = 1
    while f"session-{number}" in taken:
        number += 1
    return f"session-{number}"


def check_cluster_options(cpus_per_trial: int, max_failures: int) -> None:
    if not 1 <= cpus_per_trial <= LIMITS["threads"]:
        raise SweepError(f"--cpus-per-trial must be in [1, {LIMITS['threads']}], got {cpus_per_trial}")
    if not 0 <= max_failures <= MAX_FAILURES:
        raise SweepError(f"--max-failures must be in [0, {MAX_FAILURES}], got {max_failures}")
