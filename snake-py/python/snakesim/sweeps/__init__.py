"""Sweeps and searches on Ray: the plan and its folder (:mod:`~snakesim.sweeps.plan`), running a
sweep (:mod:`~snakesim.sweeps.sweep`), the Tune side (:mod:`~snakesim.sweeps.tune_runner`, needs the
``sweep`` extra), searches (:mod:`~snakesim.sweeps.search`) and the summary table
(:mod:`~snakesim.sweeps.summary`). Importing this package imports none of them."""


def __getattr__(name: str):
    # Its modules on first use (``snakesim.sweeps.summary`` after ``import snakesim``), none at import.
    import importlib
    import pkgutil

    if name in {module.name for module in pkgutil.iter_modules(__path__)}:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
