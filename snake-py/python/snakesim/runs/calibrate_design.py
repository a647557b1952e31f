"""A log worth fitting (``snakesim calibrate --design-targets``): joint targets that excite what
``snakesim calibrate`` fits, for a user to run on their robot (and log) before calibrating.

Three parts, one after the other (docs/calibration.md, "A log worth fitting"):

1. **Steps** (the first 40 %): a square wave of amplitude :data:`STEP_AMPLITUDE` travelling along the body,
   each joint switching every :data:`STEP_SECONDS`: steps large enough that every motor runs into its
   velocity limit (``motors.max_velocity``), then settles (the transient shows ``kp`` and ``kd``); the
   travelling wave makes the body slide and turn (friction).
2. **Sweep** (the next 30 %): a small sine (:data:`SWEEP_AMPLITUDE`) whose frequency rises from
   :data:`SWEEP_HZ` [0] to [1], delayed along the body: the motors' response below their velocity
   limit, over frequencies, where a stiffer and a more damped motor differ (``kp`` against ``kd``).
3. **Undulation** (the rest): a lateral travelling wave (:data:`WAVE_AMPLITUDE`, :data:`WAVE_HZ`), the
   body sliding sideways and forwards over the ground (``ground_friction``).

Every part starts and ends at 0 rad; the robot starts at rest.
"""

from __future__ import annotations

import math

import numpy as np

DT = 1.0 / 240.0
DEFAULT_SECONDS = 8.0
STEP_AMPLITUDE = 0.6  # rad
STEP_SECONDS = 0.75
SWEEP_AMPLITUDE = 0.15  # rad
SWEEP_HZ = (0.5, 4.0)
WAVE_AMPLITUDE = 0.5  # rad
WAVE_HZ = 1.0


def design_targets(joints: int, seconds: float = DEFAULT_SECONDS) -> np.ndarray:
    """The designed targets as (steps, joints), one row per 1/240 s physics step."""
    steps = int(round(seconds / DT))
    t = np.arange(steps) * DT
    lag = np.arange(joints) / max(joints, 1)  # each joint's delay along the body, in periods
    out = np.zeros((steps, joints))
    a, b = 0.4 * seconds, 0.7 * seconds
    # 1. Steps: joint j switches between +A and -A every STEP_SECONDS, half a period after joint j - 1
    #    is... delayed by lag[j] of a period.
    first = t < a
    phase = (t[first, None] / (2 * STEP_SECONDS) - lag[None, :]) % 1.0
    out[first] = np.where(phase < 0.5, STEP_AMPLITUDE, -STEP_AMPLITUDE)
    out[first & (t < STEP_SECONDS / 4)] = 0.0  # a moment at rest first
    # 2. Sweep: a chirp from SWEEP_HZ[0] to SWEEP_HZ[1] (linear in frequency).
    second = (t >= a) & (t < b)
    tau = t[second] - a
    span = b - a
    f0, f1 = SWEEP_HZ
    cycles = f0 * tau + (f1 - f0) * tau**2 / (2 * span)
    out[second] = SWEEP_AMPLITUDE * np.sin(2 * math.pi * (cycles[:, None] - lag[None, :]))
    # 3. Undulation: a travelling wave, faded in over half a period.
    third = t >= b
    tau = t[third] - b
    fade = np.minimum(1.0, tau * 2 * WAVE_HZ)
    out[third] = (
        WAVE_AMPLITUDE * fade[:, None] * np.sin(2 * math.pi * (WAVE_HZ * tau[:, None] - lag[None, :]))
    )
    return out


def targets_csv(names: list[str], rows: np.ndarray) -> str:
    """The targets as ``snake-cli run --targets`` reads them (``step,<joint names>``)."""
    lines = [",".join(["step", *names])]
    lines += [",".join([str(k), *(repr(float(v)) for v in row)]) for k, row in enumerate(rows, start=1)]
    return "\n".join(lines) + "\n"
