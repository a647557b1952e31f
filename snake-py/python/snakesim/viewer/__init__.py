"""Looking at runs and agents: Rerun recordings (:mod:`~snakesim.viewer.recording`), the Rerun viewer
processes (:mod:`~snakesim.viewer.processes`), replay figures and animations
(:mod:`~snakesim.viewer.replay`) and learning curves (:mod:`~snakesim.viewer.plots`). Importing this
package imports none of them."""


def __getattr__(name: str):
    # Its modules on first use (``snakesim.viewer.replay`` after ``import snakesim``), none at import.
    import importlib
    import pkgutil

    if name in {module.name for module in pkgutil.iter_modules(__path__)}:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
