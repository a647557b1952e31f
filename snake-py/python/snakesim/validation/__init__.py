"""Validation cases: snakesim held against published measurements and laws (``snakesim validate``).

Each module listed in :data:`MODULES` (``snakesim/validation/<name>.py``) exposes ``CASES``, a list of
:class:`Case`; a case runs a simulation (or evaluates a law) and returns a :class:`Result` that names the
published value, its source, the simulated value, the tolerance and whether it passed. A user who
changes a coefficient runs ``snakesim validate`` and sees at once what it does to every claim of
fidelity. ``quick`` cases take a few seconds and run in the test suite; the rest run on demand.
"""

from __future__ import annotations

import fnmatch
import importlib
from collections.abc import Callable
from dataclasses import dataclass

#: The modules that hold cases, in the order the table lists them.
MODULES = ("friction", "sand", "water")


@dataclass(frozen=True)
class Result:
    """One case's outcome."""

    name: str
    quantity: str
    published: float
    unit: str
    source: str
    simulated: float
    tolerance: str
    passed: bool


@dataclass(frozen=True)
class Case:
    """A named validation case; ``run`` simulates and compares."""

    name: str
    quick: bool
    run: Callable[[], Result]


class ValidationError(ValueError):
    """A pattern that names no case."""


def cases() -> list[Case]:
    """Every case of every module in :data:`MODULES`, in order."""
    found: list[Case] = []
    for module in MODULES:
        found.extend(importlib.import_module(f"snakesim.validation.{module}").CASES)
    return found


def select(patterns: list[str], quick: bool = False) -> list[Case]:
    """The cases whose names match any of ``patterns`` (exact names or shell globs; none: every case),
    only the quick ones with ``quick``. A pattern that matches nothing is an error."""
    every = cases()
    chosen = every
    if patterns:
        chosen = []
        for pattern in patterns:
            hits = [c for c in every if fnmatch.fnmatchcase(c.name, pattern)]
            if not hits:
                names = ", ".join(c.name for c in every)
                raise ValidationError(f"no validation case matches {pattern!r}; the cases: {names}")
            chosen.extend(c for c in hits if c not in chosen)
    if quick:
        chosen = [c for c in chosen if c.quick]
    return chosen


def relative(simulated: float, published: float) -> float:
    """|simulated - published| / |published|."""
    return abs(simulated - published) / abs(published)
