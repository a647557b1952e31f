"""Hyperparameter searches: ``snakesim search CONFIG.yaml --space space.yaml --trials T``.

Optuna picks each trial's values of the keys in the space (Tune's ``OptunaSearch``) and ASHA stops the
trials that trail the others at the same timesteps; every trial is a run directory under the search's
folder, as in a sweep (:mod:`snakesim.sweeps.sweep`). The best trial's configuration is written as
``best.yaml``, which ``snakesim train --config`` runs.

The space is YAML: every key a configuration key (dotted, or nested mappings), every value one
distribution::

    ppo.learning_rate: {loguniform: [1.0e-5, 1.0e-3]}
    ppo.ent_coef: {uniform: [0.0, 0.01]}
    ppo.n_epochs: {randint: [3, 20]}          # integers, both ends included
    ppo.n_steps: {choice: [128, 256, 512]}
    env: {reward: {progress_weight: {uniform: [0.5, 2.0]}}}
"""

from __future__ import annotations

import json
import math
import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from snakesim import extras
from snakesim.files import write_atomically
from snakesim.limits import LIMITS
from snakesim.runs import config as runconfig
from snakesim.sweeps import plan as sweep

DISTRIBUTIONS = ("uniform", "loguniform", "randint", "choice")
#: What a search maximises: the last evaluation's success rate or mean return, or the mean success
#: rate over all the run's evaluations (snakesim.sweeps.summary.with_success_auc), which rewards
#: learning early.
METRICS = ("success_rate", "mean_return", "success_auc")
BEST_FILE = "best.yaml"
IMPORTANCE_FILE = "importance.json"
#: Most keys in a space.
MAX_SPACE_KEYS = LIMITS["search_keys"]
#: ASHA lets every trial train this share of the timesteps before it may stop it.
GRACE_SHARE = 0.25
ASHA_REDUCTION_FACTOR = 3
#: Fewest evaluated trials Optuna's importance is computed from.
MIN_IMPORTANCE_TRIALS = 4


def _flatten(space: Mapping[str, Any], prefix: str = "") -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for key, value in space.items():
        path = f"{prefix}{key}"
        if isinstance(value, Mapping) and len(value) == 1 and next(iter(value)) in DISTRIBUTIONS:
            out[path] = dict(value)
        elif isinstance(value, Mapping) and value:
            out.update(_flatten(value, f"{path}."))
        else:
            raise sweep.SweepError(
                f"space {path}: expected one distribution, e.g. {{uniform: [LOW, HIGH]}} "
                f"({', '.join(DISTRIBUTIONS)})"
            )
    return out


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def load_space(path: str | os.PathLike, base: Mapping[str, Any]) -> dict[str, tuple[str, list[Any]]]:
    """The space file as ``{key: (distribution, arguments)}``; every end of a range and every choice
    is checked as a value of the configuration ``base``."""
    space = _flatten(runconfig.load_yaml(path))
    name = os.fspath(path)
    if not space:
        raise sweep.SweepError(f"space {name} is empty (expected KEY: {{uniform: [LOW, HIGH]}}, ...)")
    if len(space) > MAX_SPACE_KEYS:
        raise sweep.SweepError(f"space {name} has {len(space)} keys, at most {MAX_SPACE_KEYS}")
    out = {}
    for key, spec in space.items():
        (kind, args), where = next(iter(spec.items())), f"space {name}: {key}"
        if key in ("seed", "eval_seed"):
            raise sweep.SweepError(f"{where}: seeds are not searched")
        if not isinstance(args, list) or not args:
            raise sweep.SweepError(f"{where}: {kind} takes a list, e.g. {kind}: [1, 2]")
        if kind == "choice":
            if len(args) > sweep.MAX_GRID_VALUES:
                raise sweep.SweepError(f"{where}: {len(args)} choices, at most {sweep.MAX_GRID_VALUES}")
        else:
            if len(args) != 2 or not all(_number(a) for a in args) or not args[0] < args[1]:
                raise sweep.SweepError(f"{where}: {kind} takes [LOW, HIGH], two numbers with LOW < HIGH")
            if kind == "loguniform" and args[0] <= 0:
                raise sweep.SweepError(f"{where}: loguniform needs LOW > 0")
            if kind == "randint" and not all(isinstance(a, int) for a in args):
                raise sweep.SweepError(f"{where}: randint takes two integers")
        for value in args:
            try:
                runconfig.validate(runconfig.merge(base, sweep.nested(key, value)))
            except runconfig.ConfigError as error:
                raise runconfig.ConfigError(f"{where} = {value!r}: {error}") from None
        out[key] = (kind, list(args))
    return out


def _optuna_value(value: Any) -> Any:
    """A choice as Optuna's categorical distributions take it (a list or mapping as its JSON text)."""
    return value if value is None or isinstance(value, (bool, int, float, str)) else json.dumps(value)


def _tune_space(space: Mapping[str, tuple[str, list[Any]]]) -> dict[str, Any]:
    """The space as Tune's distributions. A list or mapping choice (``arch.pi: {choice: [[64, 64],
    ...]}``) goes to Tune and Optuna as its JSON text, the values Optuna's categorical distributions
    take without a warning; :func:`_from_tune` turns it back."""
    from ray import tune

    make = {
        "uniform": lambda a: tune.uniform(a[0], a[1]),
        "loguniform": lambda a: tune.loguniform(a[0], a[1]),
        "randint": lambda a: tune.randint(a[0], a[1] + 1),  # Tune's upper end is excluded
        "choice": lambda a: tune.choice([_optuna_value(v) for v in a]),
    }
    return {key: make[kind](args) for key, (kind, args) in space.items()}


def _optuna_space(space: Mapping[str, tuple[str, list[Any]]]) -> dict[str, Any]:
    """The space as the Optuna distributions that Tune's ``OptunaSearch`` searches: its own
    conversion of :func:`_tune_space`, so that the study :func:`importance` rebuilds has the
    search's distributions by construction."""
    from ray.tune.search.optuna import OptunaSearch

    return OptunaSearch.convert_search_space(_tune_space(space))


def _from_tune(space: Mapping[str, tuple[str, list[Any]]], params: Mapping[str, Any]) -> dict[str, Any]:
    """A trial's values as configuration values: Optuna's numpy numbers as Python numbers, and each
    choice as the space wrote it (a list or mapping back from its JSON text)."""
    out = {}
    for key, value in params.items():
        value = _plain(value)
        kind, args = space[key]
        if kind == "choice":
            value = next(a for a in args if _same(_optuna_value(a), value))
        out[key] = value
    return out


def _same(a: Any, b: Any) -> bool:
    """Equal and of one type, so that a choice of ``true`` is not taken for ``1``."""
    return type(a) is type(b) and a == b


def _overrides(base: Mapping[str, Any], params: Mapping[str, Any]) -> dict[str, Any]:
    return runconfig.merge(base, *(sweep.nested(key, value) for key, value in params.items()))


def train_search_trial(
    params: Mapping[str, Any],
    base: Mapping[str, Any],
    trials_dir: str,
    space: Mapping[str, tuple[str, list[Any]]],
) -> None:
    """The Tune trainable of a search: the base configuration with the trial's values."""
    from ray import tune

    from snakesim.sweeps.tune_runner import train_trial

    name = tune.get_context().get_trial_name()
    overrides = _overrides(base, _from_tune(space, params))
    train_trial({"trial": {"name": name, "run_dir": str(Path(trials_dir) / name), "overrides": overrides}})


def _plain(value: Any) -> Any:
    """Optuna's numpy numbers as Python numbers (the configuration is JSON)."""
    return value.item() if hasattr(value, "item") else value


def search(
    config: str | os.PathLike,
    *,
    space: str | os.PathLike,
    out: str | os.PathLike,
    trials: int,
    metric: str = METRICS[0],
    sets: Sequence[str] = (),
    address: str | None = None,
    cpus_per_trial: int = sweep.DEFAULT_CPUS_PER_TRIAL,
    max_failures: int = sweep.DEFAULT_MAX_FAILURES,
    progress: bool | None = None,
) -> int:
    """``snakesim search``: returns the exit status."""
    if metric not in METRICS:
        raise sweep.SweepError(f"--metric {metric!r}: expected one of {', '.join(METRICS)}")
    if not 1 <= trials <= sweep.MAX_TRIALS:
        raise sweep.SweepError(f"--trials must be in [1, {sweep.MAX_TRIALS}], got {trials}")
    sweep.check_cluster_options(cpus_per_trial, max_failures)
    out_path = sweep.check_new_out(out)
    (name, user_base), *_ = sweep.load_configs([config], sets).items()
    # The trials' CPUs are their threads unless the configuration sets them (as in a sweep).
    (planned,) = sweep.plan({name: user_base}, {}, 1, cpus_per_trial)
    base = planned.overrides
    resolved = runconfig.resolve(base)
    parsed = load_space(space, base)
    extras.require("sweep")
    from snakesim.sweeps import summary as sweep_summary
    from snakesim.sweeps import tune_runner

    with (
        tune_runner.connected(address, cpus_per_trial) as client,
        sweep.start_folder(
            out_path,
            sweep.new_manifest(
                "search",
                [],
                config=os.fspath(config),
                space={key: {kind: args} for key, (kind, args) in parsed.items()},
                set=list(sets),
                metric=metric,
                budget=trials,
                cpus_per_trial=cpus_per_trial,
                max_failures=max_failures,
            ),
        ),
    ):
        print(
            f"search {out_path}: {trials} trials of {name} over {', '.join(parsed)} on {client}", flush=True
        )
        # Ray is imported once connected (tune_runner.connected switches its authentication first).
        import optuna
        from ray import tune
        from ray.tune.schedulers import ASHAScheduler
        from ray.tune.search.optuna import OptunaSearch

        # Optuna's "study created" line: the display says more. Its level is restored afterwards.
        verbosity = optuna.logging.get_verbosity()
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        try:
            timesteps = resolved["timesteps"]
            tune_config = tune.TuneConfig(
                search_alg=OptunaSearch(metric=metric, mode="max", seed=resolved["seed"]),
                scheduler=ASHAScheduler(
                    time_attr="timesteps",
                    metric=metric,
                    mode="max",
                    max_t=timesteps,
                    grace_period=max(1, int(timesteps * GRACE_SHARE)),
                    reduction_factor=ASHA_REDUCTION_FACTOR,
                ),
                num_samples=trials,
            )
            trials_dir = (out_path / sweep.TRIALS_DIR).resolve()
            outcome = tune_runner.fit(
                out_path,
                tune.with_parameters(train_search_trial, base=base, trials_dir=str(trials_dir), space=parsed),
                _tune_space(parsed),
                total=trials,
                names=_numbered(),
                cpus_per_trial=cpus_per_trial,
                max_failures=max_failures,
                progress=progress,
                tune_config=tune_config,
            )
        finally:
            optuna.logging.set_verbosity(verbosity)
        done = _searched_trials(out_path, name, base, list(parsed))
        rows = sweep_summary.summarize(out_path, done)
        print(sweep_summary.format_table(rows))
        print(f"wrote {sweep_summary.write_csv(out_path, rows)}")
        for trial_name, error in outcome.errors.items():
            print(f"snakesim search: trial {trial_name} failed: {error}", file=sys.stderr)
        best = _best(out_path, done, metric)
        if best is None:
            print("snakesim search: no trial was evaluated; nothing to write", file=sys.stderr)
            return 130 if outcome.interrupted else 1
        trial, value = best
        path = write_best(out_path, _overrides(user_base, trial.point), trial.name, metric, value)
        print(
            f"best: {trial.name} ({', '.join(f'{k}={v}' for k, v in trial.point.items())}): final {metric} "
            f"{value:.4g}; wrote {path}; train it with: snakesim train --config {path}"
        )
        print(write_importance(out_path, parsed, done, metric))
        return 130 if outcome.interrupted else 0


def _numbered():
    """Trial names in the order Tune creates the trials: trial_0001, trial_0002, ..."""
    names: dict[str, str] = {}
    return lambda trial: names.setdefault(trial.trial_id, f"trial_{len(names) + 1:04d}")


def _searched_trials(
    out: Path, config: str, base: Mapping[str, Any], keys: Sequence[str]
) -> list[sweep.Trial]:
    """The trials that ran, with their values of the searched keys (from their saved config.yaml)."""
    folder = out / sweep.TRIALS_DIR
    found = []
    for run_dir in sorted(folder.iterdir()) if folder.is_dir() else []:
        try:
            saved = runconfig.load(run_dir / "config.yaml")
        except runconfig.ConfigError:
            continue
        point = {}
        for key in keys:
            value: Any = saved
            for part in key.split("."):
                value = value[part]
            point[key] = value
        found.append(sweep.Trial(run_dir.name, run_dir.name, point, saved["seed"], dict(base)))
    return found


def _best(out: Path, trials: Sequence[sweep.Trial], metric: str) -> tuple[sweep.Trial, float] | None:
    """The trial with the best final evaluation (more timesteps break ties: ASHA stopped the others)."""
    scored = [((last[metric], last["timesteps"]), trial) for trial, last in _finals(out, trials)]
    if not scored:
        return None
    (value, _), trial = max(scored, key=lambda item: item[0])
    return trial, value


def write_best(out: Path, overrides: Mapping[str, Any], name: str, metric: str, value: float) -> Path:
    """The configuration of the best trial (the searched config with its values) as YAML."""
    text = (
        f"# The best trial of the search {out} ({name}): final {metric} {value:.4g}.\n"
        f"#   snakesim train --config {out / BEST_FILE}\n" + runconfig.dump(runconfig.validate(overrides))
    )
    path = out / BEST_FILE
    write_atomically(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
    return path


def _finals(out: Path, trials: Sequence[sweep.Trial]) -> list[tuple[sweep.Trial, dict[str, float]]]:
    """Each evaluated trial with its last evaluation, success_auc included (at the timesteps where it
    ended: the end of the budget, or where ASHA stopped it)."""
    from snakesim.sweeps.summary import evaluations, with_success_auc

    found = []
    for trial in trials:
        rows = with_success_auc(evaluations(trial.run_dir(out)))
        if rows:
            found.append((trial, rows[-1]))
    return found


def importance(
    space: Mapping[str, tuple[str, list[Any]]], finals: Sequence[tuple[Mapping[str, Any], float]]
) -> dict[str, float]:
    """Optuna's importance of each searched key for ``finals`` (each trial's values and final metric,
    maximised), from Optuna's default evaluator (PED-ANOVA in Optuna 4 and 5): a study is rebuilt from
    the trials, as Tune's OptunaSearch saw them, ASHA-stopped trials with their value where they
    stopped. The importances are normalised to sum to 1."""
    import optuna

    distributions = _optuna_space(space)
    verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        study = optuna.create_study(direction="maximize")
        for point, value in finals:
            params = {key: _optuna_value(_plain(point[key])) for key in distributions}
            study.add_trial(
                optuna.trial.create_trial(params=params, distributions=distributions, value=value)
            )
        return dict(optuna.importance.get_param_importances(study))
    finally:
        optuna.logging.set_verbosity(verbosity)


def write_importance(
    out: Path, space: Mapping[str, tuple[str, list[Any]]], trials: Sequence[sweep.Trial], metric: str
) -> str:
    """``importance.json`` (each searched key's importance for the final ``metric``), and the line
    that says so; a line that says why not where there are too few evaluated trials to tell."""
    finals = [(trial, last[metric]) for trial, last in _finals(out, trials)]
    if len(finals) < MIN_IMPORTANCE_TRIALS or len({value for _, value in finals}) < 2:
        return (
            f"importance: not computed ({len(finals)} evaluated trials, {len({v for _, v in finals})} "
            f"distinct values of {metric}; it needs {MIN_IMPORTANCE_TRIALS} and 2)"
        )
    try:
        found = importance(space, [(trial.point, value) for trial, value in finals])
    except (ValueError, RuntimeError) as error:  # e.g. a saved value Optuna does not take as its choice
        return f"importance: not computed ({error})"
    record = {"metric": metric, "trials": len(finals), "importance": found}
    path = out / IMPORTANCE_FILE
    write_atomically(
        path, lambda tmp: Path(tmp).write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    )
    ranked = ", ".join(f"{key} {value:.2f}" for key, value in sorted(found.items(), key=lambda kv: -kv[1]))
    return f"importance for the final {metric} over {len(finals)} trials: {ranked}; wrote {path}"
