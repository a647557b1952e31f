"""How sure a fit is (``snakesim calibrate``'s ``intervals``): for each fitted key, the range of values
whose error stays within DELTA of the fit's when the other keys follow the error's valley.

Method (docs/calibration.md, "Intervals"): the error's curvature at the fit (a finite-difference
Hessian H over the keys mapped to [0, 1], step :data:`HESSIAN_STEP`) gives, for key i, the direction
in which the other keys best make up for a change of key i (the column i of H's pseudo-inverse, scaled
so key i moves by 1: the profile of a quadratic error). Along it, on each side, the error is simulated
at growing distances (:data:`OFFSETS`) up to the key's bound; the first that exceeds the fit's error by
more than DELTA = max(:data:`DELTA`, :data:`DELTA_FRACTION` x the fit's error) brackets the interval's
end, refined by :data:`BISECTIONS` bisections. DELTA is in the error's own units (1 is a miss of about
1 cm of the base or 0.001 rad of every joint): a change that moves the simulated run by less than a
fraction of what a motion-capture system and an encoder resolve is one the log cannot tell apart. A
failed simulation counts as exceeding it.

A side on which the error never exceeds DELTA up to the bound leaves the key "not identifiable from
this log", with the reason: the log does not pin it there (a velocity limit the joints never reach fits
at any value above their top speed).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

DELTA = 0.1
DELTA_FRACTION = 0.1
HESSIAN_STEP = 0.01
OFFSETS = (0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.4, 0.7, 1.0)
BISECTIONS = 5

#: Why a log may not pin a key, for the reason.
HINTS = {
    "motors.max_velocity": "the joints never reach the velocity limit?",
    "motors.kp": "no steps or fast changes in the targets to show the motors' response?",
    "motors.kd": "no steps or fast changes in the targets to show the motors' response?",
    "ground_friction": "the body does not slide on the ground?",
    "lateral_friction": "the body does not slide on the ground?",
    "mass_scale": "masses trade off against gains and friction; weigh the robot",
}


def delta_for(best_error: float) -> float:
    """How far above the fit's error an interval ends."""
    return max(DELTA, DELTA_FRACTION * best_error)


def _hessian_points(center: np.ndarray, h: float) -> list[np.ndarray]:
    dim = len(center)
    points = [center.copy()]
    for i in range(dim):
        for s in (1, -1):
            p = center.copy()
            p[i] += s * h
            points.append(p)
    for i in range(dim):
        for j in range(i + 1, dim):
            for si, sj in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
                p = center.copy()
                p[i] += si * h
                p[j] += sj * h
                points.append(p)
    return points


def _hessian(errors: list[float], dim: int, h: float) -> np.ndarray:
    f = [e if math.isfinite(e) else np.nan for e in errors]
    f0 = f[0]
    H = np.zeros((dim, dim))
    for i in range(dim):
        H[i, i] = (f[1 + 2 * i] - 2 * f0 + f[2 + 2 * i]) / h**2
    k = 1 + 2 * dim
    for i in range(dim):
        for j in range(i + 1, dim):
            pp, pm, mp, mm = f[k : k + 4]
            H[i, j] = H[j, i] = (pp - pm - mp + mm) / (4 * h**2)
            k += 4
    return np.nan_to_num(H, nan=0.0)


def valley_directions(H: np.ndarray) -> np.ndarray:
    """Row i: the direction in [0, 1]^n along which key i moves by 1 and the others follow the valley
    of the quadratic error 0.5 dx' H dx (the unit vector of key i where the curvature says nothing)."""
    dim = H.shape[0]
    values, vectors = np.linalg.eigh((H + H.T) / 2)
    top = float(np.max(values)) if dim else 0.0
    keep = values > max(top, 0.0) * 1e-8
    P = (vectors[:, keep] / values[keep]) @ vectors[:, keep].T if np.any(keep) else np.zeros_like(H)
    rows = []
    for i in range(dim):
        if P[i, i] > 0:
            rows.append(P[:, i] / P[i, i])
        else:
            e = np.zeros(dim)
            e[i] = 1.0
            rows.append(e)
    return np.array(rows)


def intervals(
    evaluate: Callable[[Sequence[np.ndarray]], list[float]],
    keys: Sequence[str],
    to_value: Callable[[int, float], float],
    best_x: np.ndarray,
    best_error: float,
) -> tuple[dict[str, dict], int]:
    """Each key's interval (``low``, ``high``, ``identifiable``, ``reason``) and the simulations spent.
    ``evaluate`` maps a batch of points in [0, 1]^n to errors; ``to_value(i, u)`` is key i's value at
    ``u``."""
    dim = len(keys)
    best_x = np.clip(np.asarray(best_x, dtype=float), 0.0, 1.0)
    delta = delta_for(best_error)
    threshold = best_error + delta
    h = HESSIAN_STEP
    center = np.clip(best_x, h, 1 - h)
    points = _hessian_points(center, h)
    errors = evaluate(points)
    spent = len(points)
    directions = valley_directions(_hessian(errors, dim, h))

    def point(i: int, t: float) -> np.ndarray:
        return np.clip(best_x + t * directions[i], 0.0, 1.0)

    # Distances to the key's bound on each side, and the walk out to it.
    walks: list[tuple[int, int, list[float]]] = []
    for i in range(dim):
        for side in (-1, 1):
            room = best_x[i] if side < 0 else 1.0 - best_x[i]
            ts = [t for t in OFFSETS if t < room] + ([room] if room > 0 else [])
            walks.append((i, side, [side * t for t in ts]))
    batch = [point(i, t) for i, _, ts in walks for t in ts]
    errors = evaluate(batch) if batch else []
    spent += len(batch)
    brackets: list[list[float] | None] = []  # [inside t, outside t] or None: never exceeds
    k = 0
    for _, _, ts in walks:
        inside, found = 0.0, None
        for t in ts:
            e = errors[k]
            k += 1
            if found is None:
                if not (math.isfinite(e) and e <= threshold):
                    found = [inside, t]
                else:
                    inside = t
        brackets.append(found)
    for _ in range(BISECTIONS):
        open_ = [(n, b) for n, b in enumerate(brackets) if b is not None]
        if not open_:
            break
        mids = [(b[0] + b[1]) / 2 for _, b in open_]
        errs = evaluate([point(walks[n][0], t) for (n, _), t in zip(open_, mids)])
        spent += len(mids)
        for (_, b), t, e in zip(open_, mids, errs):
            if math.isfinite(e) and e <= threshold:
                b[0] = t
            else:
                b[1] = t
    result: dict[str, dict] = {}
    for i, key in enumerate(keys):
        ends, open_sides = {}, []
        for n, (j, side, _) in enumerate(walks):
            if j != i:
                continue
            b = brackets[n]
            if b is None:
                u = 0.0 if side < 0 else 1.0
                open_sides.append("lower" if side < 0 else "upper")
            else:
                u = float(np.clip(best_x[i] + (b[0] + b[1]) / 2, 0.0, 1.0))
            ends[side] = to_value(i, u)
        entry: dict = {"low": ends[-1], "high": ends[1], "identifiable": not open_sides, "reason": None}
        if open_sides:
            sides = " and ".join(open_sides)
            entry["reason"] = (
                f"not identifiable from this log: the error stays within {delta:.3g} of the fit's out to "
                f"the {sides} bound{'s' if len(open_sides) > 1 else ''} "
                f"({HINTS.get(key, 'the log does not excite it?')})"
            )
        result[key] = entry
    return result, spent
