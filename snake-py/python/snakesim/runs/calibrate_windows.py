"""Multiple shooting for ``snakesim calibrate``: the logged state each window restarts from.

Over seconds, contact makes a robot's run chaotic: two runs whose kp differ by 1e-4 end centimetres
apart, so an error summed over a whole run is a landscape of needles. Cut into windows (default
:data:`DEFAULT_WINDOW_SECONDS`), each restarted from the state the log holds at its start, a small
error in a parameter stays a small error (docs/calibration.md, "Windows").

The state a window starts from (:func:`window_states`): the base's centre-of-mass pose (the log's
``base_*`` columns), its world-frame linear and angular velocity, the joint angles and the joint
velocities. Velocities come from the log's own columns when it has them (``base_vx .. base_wz``,
``qd0 ..``), and are otherwise estimated from the positions by a backward difference over one step
(:func:`estimate_velocities`): Bullet integrates positions with the velocity after the step
(semi-implicit Euler), so for a simulator's log the backward difference is the velocity to rounding
(1e-13 rad/s on the smooth test log), and for a real log sampled at 240 Hz it is the velocity the
motion shows, with the sensor's noise divided by the step (see the docs for smoothing a noisy log).
"""

from __future__ import annotations

import numpy as np

#: The physics step, s.
DT = 1.0 / 240.0
#: Default window length, s: short enough that the truth's error stays smooth in every parameter on the
#: smooth random log (docs/calibration.md), long enough for a motor's step response (kp, kd).
DEFAULT_WINDOW_SECONDS = 0.25


def window_steps(seconds: float) -> int:
    """A window length in seconds as whole physics steps (at least 1 when ``seconds`` >= one step)."""
    return int(round(seconds / DT))


def _multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Hamilton products of (x, y, z, w) quaternions."""
    x1, y1, z1, w1 = a.T
    x2, y2, z2, w2 = b.T
    return np.stack(
        [
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        ],
        axis=1,
    )


def estimate_velocities(now: np.ndarray, before: np.ndarray, joints: int) -> np.ndarray:
    """Velocities at log rows ``now`` from the rows one step ``before`` (both (k, 7 + joints)): the base's
    linear velocity, its world-frame angular velocity (the rotation from one orientation to the next,
    as an angle about an axis, over the step: the inverse of Bullet's exponential-map update) and the
    joint velocities, as (k, 6 + joints)."""
    linear = (now[:, :3] - before[:, :3]) / DT
    conjugate = before[:, 3:7] * np.array([-1.0, -1.0, -1.0, 1.0])
    turn = _multiply(now[:, 3:7], conjugate)
    turn *= np.where(turn[:, 3:4] < 0, -1.0, 1.0)  # the short way round
    sine = np.linalg.norm(turn[:, :3], axis=1)
    angle = 2.0 * np.arctan2(sine, turn[:, 3])
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(sine > 0, angle / np.where(sine > 0, sine, 1.0), 2.0) / DT
    angular = turn[:, :3] * scale[:, None]
    qd = (now[:, 7 : 7 + joints] - before[:, 7 : 7 + joints]) / DT
    return np.hstack([linear, angular, qd])


def window_states(log: np.ndarray, joints: int, window: int) -> np.ndarray:
    """The states windows of ``window`` steps restart from: row i is the state after step (i + 1) x
    ``window`` (snake-core's ``Windows::states``: pose, velocities, joint angles, joint velocities)."""
    steps = log.shape[0]
    ends = np.arange(window, steps, window)  # step s is log row s - 1
    rows = log[ends - 1]
    if log.shape[1] >= 13 + 2 * joints:  # the log holds the velocities
        velocities = rows[:, 7 + joints : 13 + 2 * joints]
    else:
        # Before step 1 (a window of one step) the robot is at rest: its pose is not logged, so the
        # first row's velocity is taken as the second's.
        before = log[np.maximum(ends - 2, 0)]
        velocities = estimate_velocities(rows, before, joints)
        if len(ends) and ends[0] == 1 and steps > 1:
            velocities[0] = estimate_velocities(log[1:2], log[0:1], joints)[0]
    out = np.hstack([rows[:, :7], velocities[:, :6], rows[:, 7 : 7 + joints], velocities[:, 6:]])
    return np.ascontiguousarray(out, dtype=np.float64)
