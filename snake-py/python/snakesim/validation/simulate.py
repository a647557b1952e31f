"""What the validation cases share: the repository's robots, joint targets of a robot file's own gait
and of Maladen et al.'s travelling sine wave (the gait library's), a run of a robot in a world
(``_core.simulate_robot``), and the box of two halves that the friction and sand cases drop and slide.
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


def sandfish_targets(
    robot: Path,
    amplitude: float,
    wavelength: float,
    frequency: float,
    segment: float,
    seconds: float,
) -> npt.NDArray[np.float64]:
    """Maladen et al.'s travelling sine wave ``y = A sin(2 pi (x / lambda + f t))`` from the gait library
    (``snake_core::gait::sandfish``) on the robot's yaw joints, one row per physics step: each segment
    of ``segment`` metres takes the wave's slope at its centre, each joint the difference of its two
    segments' angles."""
    steps = int(round(seconds * RATE))
    return _core.sandfish_targets(os.fspath(robot), amplitude, wavelength, frequency, segment, steps)


def run(
    robot: Path,
    targets: npt.NDArray[np.float64],
    world: Path | None = None,
    start: tuple[float, float, float, float] | None = None,
) -> npt.NDArray[np.float64]:
    """The base pose (x, y, z, qx, qy, qz, qw) after every physics step."""
    return run_with_joints(robot, targets, world, start)[0]


def run_with_joints(
    robot: Path,
    targets: npt.NDArray[np.float64],
    world: Path | None = None,
    start: tuple[float, float, float, float] | None = None,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The base pose after every physics step, as :func:`run`, and the joint angles (steps, joints)."""
    return _core.simulate_robot(
        os.fspath(robot),
        np.ascontiguousarray(targets),
        None if world is None else os.fspath(world),
        start,
    )


def two_halves(name: str, size: tuple[float, float, float], mass: float) -> str:
    """The URDF of a box made of two equal halves end to end along x, each ``size`` (length, width,
    height; metres) and ``mass`` kg with its box's inertia (to four significant figures, as the cases
    were first written), joined by a yaw joint where they meet (a robot has at least one joint; the
    cases hold it straight). The base is the front half; the body lies along -x from its centre."""
    lx, ly, lz = size
    inertia = [mass / 12.0 * (b * b + c * c) for b, c in ((ly, lz), (lx, lz), (lx, ly))]
    box = f'<geometry><box size="{lx!r} {ly!r} {lz!r}"/></geometry>'
    tensor = '<inertia ixx="{:.4g}" ixy="0" ixz="0" iyy="{:.4g}" iyz="0" izz="{:.4g}"/>'.format(*inertia)
    back = f'<origin xyz="{-lx / 2!r} 0 0"/>'
    return f"""<?xml version="1.0"?>
<robot name="{name}">
  <link name="a">
    <inertial><mass value="{mass!r}"/>{tensor}</inertial>
    <collision>{box}</collision>
  </link>
  <link name="b">
    <inertial>{back}<mass value="{mass!r}"/>{tensor}</inertial>
    <collision>{back}{box}</collision>
  </link>
  <joint name="j" type="revolute">
    <parent link="a"/><child link="b"/>{back}<axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="100" velocity="5"/>
  </joint>
</robot>
"""
