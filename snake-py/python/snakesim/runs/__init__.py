"""Training runs: the run configuration (:mod:`~snakesim.runs.config`), the run directory's files
(:mod:`~snakesim.runs.rundir`), the native trainer (:mod:`~snakesim.runs.native`) and the SB3 one
(:mod:`~snakesim.runs.sb3_trainer`), what training ends with (:mod:`~snakesim.runs.results`), SB3
policies (:mod:`~snakesim.runs.policies`) and the export of native policies to SB3
(:mod:`~snakesim.runs.export`). Importing this package imports none of them."""


def __getattr__(name: str):
    # Its modules on first use (``snakesim.runs.onnx`` after ``import snakesim``), none at import.
    import importlib
    import pkgutil

    if name in {module.name for module in pkgutil.iter_modules(__path__)}:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
