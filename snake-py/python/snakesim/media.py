"""Media beyond the rigid world (docs/media.md): Li et al.'s granular law and plate experiment.

``rft_alpha(beta, gamma)`` is the Rust law the simulator applies (``snake_core::media::granular::alpha``),
over numpy arrays; ``probe(world, ...)`` is ``snake-cli probe``.
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np
import numpy.typing as npt

from snakesim import _core

__all__ = ["GENERIC", "probe", "rft_alpha"]

#: Li, Zhang and Goldman 2013's generic coefficients (Science 339:1408), as the Rust crate holds them.
GENERIC = {
    "A00": 0.206,
    "A10": 0.169,
    "B11": 0.212,
    "B01": 0.358,
    "B-11": 0.055,
    "C11": -0.124,
    "C01": 0.253,
    "C-11": 0.007,
    "D10": 0.088,
}


def rft_alpha(
    beta: npt.ArrayLike, gamma: npt.ArrayLike, coefficients: str | dict[str, float] = "generic"
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Li et al.'s ``(alpha_x, alpha_z)`` (dimensionless; times ``zeta`` in N/m^3 for a medium) for the
    plate angle ``beta`` and the intrusion angle ``gamma`` in radians (arrays of one shape, or scalars,
    broadcast together). In ``[-pi/2, pi/2]`` both it is their Eq. 1; other angles follow by their
    symmetries (period pi in beta; the mirror ``(beta, gamma) -> (-beta, pi - gamma)`` flips alpha_x).
    ``alpha_z(0, pi/2) = 1``: a horizontal plate pushed straight down. ``coefficients``: ``"generic"``
    or a dict of the nine coefficients ``A00 A10 B11 B01 B-11 C11 C01 C-11 D10``."""
    b, g = np.broadcast_arrays(np.asarray(beta, dtype=np.float64), np.asarray(gamma, dtype=np.float64))
    ax, az = _core.rft_alpha(np.ascontiguousarray(b), np.ascontiguousarray(g), json.dumps(coefficients))
    # ascontiguousarray makes a scalar one element long: the results take the inputs' shape back.
    return ax.reshape(b.shape), az.reshape(b.shape)


def probe(
    world: str | os.PathLike[str],
    plate: tuple[float, float],
    beta: float,
    gamma: float,
    depth: float,
    speed: float = 0.01,
) -> dict[str, Any]:
    """Li et al.'s plate experiment in the first granular medium of ``world`` (``snake-cli probe``):
    a plate ``(length, width)`` metres at the angle of attack ``beta`` and intrusion angle ``gamma``
    (degrees, each in [-90, 90]), centre ``depth`` metres below the surface, moving at ``speed`` m/s.
    Returns ``{"zeta": ..., "result": {force_x, force_z, stress_x, stress_z, law_x, law_z, alpha_x,
    alpha_z, elements}}`` (N, N/m^2; x along the motion's horizontal direction, z up)."""
    length, width = plate
    return json.loads(_core.probe_plate(os.fspath(world), length, width, beta, gamma, depth, speed))
