"""Skin friction (docs/friction.md) against its published sources.

- Hu, Nirody, Scott and Shelley 2009 (PNAS 106:10081, "The mechanics of slithering locomotion"): a snake
  whose skin is isotropic makes no net progress with lateral undulation on flat ground.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from snakesim.validation import Case, Result
from snakesim.validation.simulate import ROBOTS, robot_gait_targets, run

HU = "Hu et al. 2009, PNAS 106:10081 (isotropic skin: no net progress)"


def _flat17_with_skin(folder: Path, forward: float, backward: float, transverse: float) -> Path:
    robot = folder / "flat-17-skin.yaml"
    text = (ROBOTS / "flat-17.yaml").read_text()
    text = text.replace("urdf: flat-17.urdf", f"urdf: {ROBOTS / 'flat-17.urdf'}")
    text += f"skin_friction: {{forward: {forward}, backward: {backward}, transverse: {transverse}}}\n"
    robot.write_text(text)
    return robot


def _isotropic_no_progress() -> Result:
    # flat-17: 17 links of 0.1 m, its file's sine gait (period 6 s); two periods after one of warm-up.
    with tempfile.TemporaryDirectory() as folder:
        world = Path(folder) / "world.yaml"
        world.write_text("ground_friction: 1.0\n")
        robot = _flat17_with_skin(Path(folder), 0.1, 0.1, 0.1)
        period, length = 6.0, 1.7
        targets = robot_gait_targets(robot, 3 * period)
        base = run(robot, targets, world)
    dt = 1.0 / 240.0
    start = int(period / dt)
    moved = np.hypot(*(base[-1, :2] - base[start, :2]))
    per_cycle = moved / length / 2.0
    return Result(
        name="friction.isotropic-skin-no-progress",
        quantity="distance per cycle, flat-17, isotropic skin 0.1",
        published=0.0,
        unit="body lengths/cycle",
        source=HU,
        simulated=float(per_cycle),
        tolerance="< 0.02 body lengths per cycle",
        passed=bool(per_cycle < 0.02),
    )


CASES = [
    Case("friction.isotropic-skin-no-progress", True, _isotropic_no_progress),
]
