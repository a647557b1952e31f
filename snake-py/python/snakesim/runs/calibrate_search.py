"""IPOP-CMA-ES for ``snakesim calibrate``: CMA-ES restarted with a doubled population until the budget
is spent or two runs agree (Auger and Hansen 2005, "A restart CMA evolution strategy with increasing
population size"), over the fitted keys mapped to [0, 1].

Stop rules (docs/calibration.md, "Restarts"):

- a run ends when its generation's candidates all lie within ``tolerance`` (of [0, 1]) of each other,
  when its best error has improved by less than max(:data:`STALL_FRACTION` x itself,
  :data:`STALL_ERROR`) over the last :data:`STALL_GENERATIONS` generations (it has settled: further
  digits of an error far below what a log resolves change nothing), or when ``cmaes`` says it should
  stop (its own TolX, TolFun, condition and stagnation rules);
- the search ends when the next generation would pass ``max_evals`` simulations (a partial generation
  cannot be told to CMA-ES), after ``max_restarts`` restarts, or when a restarted run ends within
  :data:`AGREE` (of [0, 1], every key) of the best point so far with an error within :data:`AGREE_ERROR`
  of it (or :data:`STALL_ERROR`): two runs from different random starts found the same valley, so
  further restarts would too.

The first run starts at the middle of the box, every restart at a uniformly random point in
[0.1, 0.9]^n (from ``seed``), with step size 0.3 and population ``population`` x 2^r. A candidate whose
simulation fails scores ``math.inf``: it ranks last (CMA-ES is told :data:`FAILED`, or twice the
generation's largest finite error when that is more) and is never the fit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

#: What CMA-ES is told of a candidate whose simulation failed (or twice the generation's largest finite
#: error, when that is more), so that it ranks last; the candidate's own error is ``math.inf``.
FAILED = 1e12
#: A run has settled when its best error improved by less than max(STALL_FRACTION x it, STALL_ERROR) over
#: the last STALL_GENERATIONS generations (STALL_ERROR is a hundredth of the intervals' DELTA).
STALL_GENERATIONS = 15
STALL_FRACTION = 0.01
STALL_ERROR = 1e-3
#: Two runs agree when their best points are this close in every key (of [0, 1]) ...
AGREE = 0.01
#: ... and their errors within this fraction of each other (or STALL_ERROR apart).
AGREE_ERROR = 0.05


@dataclass
class Run:
    """One CMA-ES run of the search (the JSON's ``restarts``)."""

    population: int
    simulations: int = 0
    generations: int = 0
    best_x: list[float] = field(default_factory=list)
    best_error: float = math.inf
    stopped: str = ""


@dataclass
class Search:
    best_x: np.ndarray
    best_error: float
    simulations: int
    failed: int
    generations: int
    runs: list[Run]
    stopped: str


def ipop(
    evaluate: Callable[[Sequence[np.ndarray]], list[float]],
    dim: int,
    *,
    population: int,
    max_evals: int,
    seed: int = 0,
    tolerance: float = 1e-3,
    max_restarts: int = 9,
    progress: Callable[[int, float, int], None] | None = None,
) -> Search:
    """Minimises ``evaluate`` (a generation of points in [0, 1]^dim -> their errors) by IPOP-CMA-ES;
    ``progress(simulations, best error, run)`` after each generation."""
    from cmaes import CMA

    rng = np.random.default_rng(seed)
    simulations = failed = generations = 0
    best_x, best_error = np.full(dim, 0.5), math.inf
    runs: list[Run] = []
    stopped = "max_restarts"
    for r in range(max_restarts + 1):
        size = population * 2**r
        if simulations + size > max_evals:
            stopped = "max_evals"
            break
        mean = np.full(dim, 0.5) if r == 0 else rng.uniform(0.1, 0.9, dim)
        optimizer = CMA(
            mean=mean,
            sigma=0.3,
            bounds=np.array([[0.0, 1.0]] * dim),
            seed=int(rng.integers(1 << 31)),
            population_size=size,
        )
        run = Run(population=size)
        runs.append(run)
        before_x, before_error = best_x, best_error  # what the earlier runs found
        run_x = mean
        history: list[float] = []  # the run's best error after each generation
        while True:
            if simulations + size > max_evals:
                run.stopped = stopped = "max_evals"
                break
            xs = [optimizer.ask() for _ in range(size)]
            errors = evaluate(xs)
            simulations += size
            run.simulations += size
            generations += 1
            run.generations += 1
            finite = [e for e in errors if math.isfinite(e)]
            failed += size - len(finite)
            last = min(max([FAILED, *(2 * e for e in finite)]), np.finfo(np.float64).max)
            optimizer.tell([(x, e if math.isfinite(e) else last) for x, e in zip(xs, errors)])
            if finite:
                k = int(np.argmin(errors))
                if errors[k] < run.best_error:
                    run.best_error, run_x = errors[k], xs[k]
                if errors[k] < best_error:
                    best_x, best_error = xs[k], errors[k]
            if progress:
                progress(simulations, best_error, r)
            history.append(run.best_error)
            spread = float(np.max(np.ptp(np.array(xs), axis=0)))
            if spread < tolerance:
                run.stopped = "converged"
                break
            if len(history) > STALL_GENERATIONS:
                then, now = history[-1 - STALL_GENERATIONS], history[-1]
                if math.isfinite(now) and then - now < max(STALL_FRACTION * now, STALL_ERROR):
                    run.stopped = "settled"
                    break
            if optimizer.should_stop():
                run.stopped = "cmaes"
                break
        run.best_x = [float(v) for v in run_x]
        if stopped == "max_evals":
            break
        if r > 0 and math.isfinite(run.best_error):
            if _agree(np.asarray(run_x), run.best_error, before_x, before_error):
                stopped = "agreed"
                break
    return Search(best_x, best_error, simulations, failed, generations, runs, stopped)


def _agree(x: np.ndarray, error: float, best_x: np.ndarray, best_error: float) -> bool:
    close = float(np.max(np.abs(x - best_x))) <= AGREE
    return close and abs(error - best_error) <= max(AGREE_ERROR * max(error, best_error), STALL_ERROR)
