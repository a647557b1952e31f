"""Unpickling without running a pickle's code: the one kind of pickle snakesim reads, SB3's
``VecNormalize`` statistics (``vecnormalize.pkl``), through an allow-list of the classes and functions
such a file names.

``pickle.load`` calls whatever callable a pickle names, so a file from elsewhere could run any code on
load. Here every name a pickle looks up goes through :meth:`StatisticsUnpickler.find_class`, which
returns only the allowed ones and refuses the file otherwise, before anything it names is called.
"""

from __future__ import annotations

import io
import pickle
from typing import Any

# What a VecNormalize pickle holds: the wrapper and its running statistics, numpy arrays (rebuilt from
# their bytes; older pickles rebuild them with _reconstruct) and scalars, and the gymnasium spaces it
# keeps, with their random generators (numpy's own unpickling helpers, which call nothing else).
_ALLOWED: dict[str, frozenset[str]] = {
    "stable_baselines3.common.vec_env.vec_normalize": frozenset({"VecNormalize"}),
    "stable_baselines3.common.running_mean_std": frozenset({"RunningMeanStd"}),
    "gymnasium.spaces.box": frozenset({"Box"}),
    "numpy": frozenset({"ndarray", "dtype"}),
    "numpy._core.multiarray": frozenset({"_reconstruct", "scalar"}),
    "numpy._core.numeric": frozenset({"_frombuffer"}),
    "numpy.random._pickle": frozenset({"__generator_ctor", "__bit_generator_ctor"}),
    "numpy.random._pcg64": frozenset({"PCG64"}),
    "numpy.random.bit_generator": frozenset({"SeedSequence", "__pyx_unpickle_SeedSequence"}),
}
# numpy 1.x wrote numpy.core.*; numpy 2 has them as numpy._core.* (and importing numpy.core warns).
_RENAMED = {"numpy.core.multiarray": "numpy._core.multiarray", "numpy.core.numeric": "numpy._core.numeric"}


class RefusedPickle(ValueError):
    """A pickle that names something a statistics file does not hold; the message names it."""


class StatisticsUnpickler(pickle.Unpickler):
    """An unpickler that looks up only the names of :data:`_ALLOWED`."""

    def find_class(self, module: str, name: str) -> Any:
        module = _RENAMED.get(module, module)
        if name not in _ALLOWED.get(module, ()):
            raise RefusedPickle(f"the pickle names {module}.{name}, which a VecNormalize file does not hold")
        return super().find_class(module, name)

    def persistent_load(self, pid: Any) -> Any:
        raise RefusedPickle("the pickle names a persistent object, which a VecNormalize file does not hold")


def load_statistics(data: bytes) -> Any:
    """The object pickled in ``data``, built from allowed names only (RefusedPickle otherwise; the
    errors of a malformed pickle pass through)."""
    return StatisticsUnpickler(io.BytesIO(data)).load()
