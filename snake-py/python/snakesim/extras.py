"""The package's optional extras (snake-py/pyproject.toml), and the one error a missing one gives.

The base install (``pip install snakesim``) runs the envs, the native trainer, ``evaluate``, ``plot``,
``replay`` and Rerun recordings. What needs more calls :func:`require` before importing it, so that a
missing extra is one line naming the ``pip install`` that fixes it, from Python (an ImportError) and
from the ``snakesim`` command alike.
"""

from __future__ import annotations

import importlib.util

# extra -> (what needs it, the modules it brings that are checked). The extras' package lists are in
# snake-py/pyproject.toml.
EXTRAS: dict[str, tuple[str, tuple[str, ...]]] = {
    "sb3": (
        "Stable-Baselines3 support (the SB3 trainer, SnakeVecEnv, export --sb3, SB3 .zip models)",
        ("stable_baselines3", "torch", "tensorboard"),
    ),
    "sweep": ("Running sweeps and searches on Ray (snakesim sweep, snakesim search)", ("ray", "optuna")),
}


class MissingExtra(ImportError):
    """An optional dependency is not installed; the message names the extra that installs it."""

    def __init__(self, extra: str, module: str, what: str) -> None:
        super().__init__(
            f"{what} needs the Python module {module!r}, which is not installed: "
            f"pip install 'snakesim[{extra}]'",
            name=module,
        )
        self.extra = extra


def missing(extra: str) -> str | None:
    """The first module of ``extra`` that is not installed, or None (nothing is imported)."""
    for module in EXTRAS[extra][1]:
        if importlib.util.find_spec(module) is None:
            return module
    return None


def available(extra: str) -> bool:
    return missing(extra) is None


def require(extra: str, what: str | None = None) -> None:
    """Raises :class:`MissingExtra` (an ImportError) unless every module of ``extra`` is installed;
    ``what`` says what needs it (default: the extra's own description)."""
    module = missing(extra)
    if module is not None:
        raise MissingExtra(extra, module, what or EXTRAS[extra][0])
