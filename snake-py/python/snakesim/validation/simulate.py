"""What the validation cases share: the repository's robots, joint targets of a robot file's own gait
and of Maladen et al.'s travelling sine wave, and a run of a robot in a world (``_core.simulate_robot``).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import numpy.typing as npt

from snakesim import _core

#: Physics steps per second of every robot (pybullet's default 1/240 s).
RATE = 240.0


def _robots() -> Path:
    # The cases read robot files from a checkout of the repository (snake-py/python/snakesim/validation
    # lies four folders below its root); SNAKESIM_ROBOTS names another folder.
    named = os.environ.get("SNAKESIM_ROBOTS")
    return Path(named) if named else Path(__file__).resolve().parents[4] / "robots"


ROBOTS = _robots()


def robot_gait_targets(robot: Path, seconds: float) -> npt.NDArray[np.float64]:
    """The robot file's own gait as joint targets, one row per physics step."""
    return _core.robot_gait_targets(os.fspath(robot), int(round(seconds * RATE)))


def sine_wave_targets(
    joints: int,
    segment: float,
    amplitude: float,
    wavelength: float,
    frequency: float,
    seconds: float,
) -> npt.NDArray[np.float64]:
    """Joint angles that bend a chain of ``joints + 1`` segments of ``segment`` metres into Maladen et
    al.'s travelling sine wave ``y = A sin(2 pi (x / lambda + f t))`` (travelling from head to tail as
    the body lies along -x from the head): each segment takes the slope of the wave at its centre, each
    joint the difference of its two segments' angles."""
    t = np.arange(1, int(round(seconds * RATE)) + 1) / RATE
    k = 2.0 * np.pi / wavelength
    x = -(np.arange(joints + 1) + 0.5) * segment  # segment centres along -x from the head
    heading = np.arctan(amplitude * k * np.cos(k * x[None, :] + 2.0 * np.pi * frequency * t[:, None]))
    # Joint i joins segment i (parent) and segment i + 1 (child): the child's angle relative to it.
    return heading[:, 1:] - heading[:, :-1]


def run(
    robot: Path,
    targets: npt.NDArray[np.float64],
    world: Path | None = None,
    start: tuple[float, float, float, float] | None = None,
) -> npt.NDArray[np.float64]:
    """The base pose (x, y, z, qx, qy, qz, qw) after every physics step."""
    base, _ = _core.simulate_robot(
        os.fspath(robot),
        np.ascontiguousarray(targets),
        None if world is None else os.fspath(world),
        start,
    )
    return base
