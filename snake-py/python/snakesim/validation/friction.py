"""Skin friction (docs/friction.md) against its published sources.

- Hu, Nirody, Scott and Shelley 2009 (PNAS 106:10081, "The mechanics of slithering locomotion"): a snake
  whose skin is isotropic makes no net progress with lateral undulation on flat ground.
- Coulomb's law of friction on a slope (docs/friction.md, "Coulomb on a slope"): a block whose skin has
  the coefficient mu in the direction it slides accelerates at g (sin t - mu cos t) down a slope of t,
  and holds where mu >= tan t, whatever its other two coefficients.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from snakesim.validation import Case, Result, relative
from snakesim.validation.simulate import ROBOTS, robot_gait_targets, run, two_halves

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


#: docs/friction.md's block: 0.2 kg, 0.2 x 0.06 x 0.04 m, as two 0.1 kg halves on a yaw joint held
#: straight (a robot has at least one joint); the skin axis is each link's +x, the block's length.
BLOCK = two_halves("block", (0.1, 0.06, 0.04), 0.1)
SLOPE = math.radians(10.0)
G = 9.81
#: Bullet's damping of every multibody link (btMultiBody's default linear damping, pybullet's too):
#: a force -m (k1 v + k2 v |v|) with k1 = k2 = 0.04, which Coulomb's law alone leaves out.
DAMPING = 0.04
#: The slide is measured from 0.5 s, when the block, started level above the tilted plane, has landed
#: flat on it, to 2 s (docs/friction.md's two seconds).
FROM, TO = 120, 480
COULOMB = "Coulomb's law, a = g (sin t - mu cos t), with Bullet's link damping (docs/friction.md)"


def coulomb_slide(mu: float, speed: float, steps: int) -> float:
    """Distance (m) a block sliding at ``speed`` down the slope covers in ``steps`` steps of 1/240 s:
    Coulomb's law, a = g (sin t - mu cos t), less Bullet's damping, stepped as Bullet steps (the speed
    first, then the position)."""
    accel, v, x, dt = G * (math.sin(SLOPE) - mu * math.cos(SLOPE)), speed, 0.0, 1.0 / 240.0
    for _ in range(steps):
        v += (accel - DAMPING * v - DAMPING * v * abs(v)) * dt
        x += v * dt
    return x


def _slide(skin: tuple[float, float, float], yaw: float) -> np.ndarray:
    """The block's distance down the slope after every step (m), started level 4 cm above the origin
    of ``ground: {slope: {degrees: 10}}`` (rising towards +y) with heading ``yaw``, ground friction 1."""
    forward, backward, transverse = skin
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "block.urdf").write_text(BLOCK)
        robot = Path(folder) / "block.yaml"
        robot.write_text(
            "urdf: block.urdf\ninertia: file\nmotors: {kp: 1, kd: 1}\n"
            f"skin_friction: {{forward: {forward}, backward: {backward}, transverse: {transverse}}}\n"
        )
        world = Path(folder) / "world.yaml"
        world.write_text("ground: {slope: {degrees: 10}}\nground_friction: 1.0\n")
        base = run(robot, np.zeros((TO, 1)), world, (0.0, 0.0, 0.04, yaw))
    return -base[:, 1] / math.cos(SLOPE)


#: The slope cases: name, skin (forward, backward, transverse), heading, the sliding direction's mu.
SLIDES = {
    "head-first": ((0.05, 0.3, 0.3), -math.pi / 2, 0.05),
    "tail-first": ((0.3, 0.1, 0.3), math.pi / 2, 0.1),
    "sideways": ((0.3, 0.3, 0.15), 0.0, 0.15),
}


def _slope(which: str) -> Result:
    skin, yaw, mu = SLIDES[which]
    down = _slide(skin, yaw)
    speed = (down[FROM - 1] - down[FROM - 2]) * 240.0
    simulated = float(down[TO - 1] - down[FROM - 1])
    published = coulomb_slide(mu, speed, TO - FROM)
    return Result(
        name=f"friction.slope-{which}",
        quantity=f"slide from 0.5 to 2 s down a 10 degree slope, skin {skin[0]:g}/{skin[1]:g}/{skin[2]:g}, "
        f"{which} (mu {mu:g})",
        published=published,
        unit="m",
        source=COULOMB,
        simulated=simulated,
        tolerance="2 %",
        passed=bool(relative(simulated, published) <= 0.02),
    )


def _slope_holds() -> Result:
    # Sliding head first against forward 0.3 > tan 10 deg = 0.176; the other two are 0.05.
    down = _slide((0.3, 0.05, 0.05), -math.pi / 2)
    simulated = float(abs(down[TO - 1] - down[FROM - 1]))
    return Result(
        name="friction.slope-holds",
        quantity="slide from 0.5 to 2 s, 10 degree slope, skin 0.3/0.05/0.05 head first (0.3 > tan 10 deg)",
        published=0.0,
        unit="m",
        source="Coulomb's law (a block holds while mu >= tan t)",
        simulated=simulated,
        tolerance="< 1 mm",
        passed=bool(simulated < 1e-3),
    )


CASES = [
    Case("friction.isotropic-skin-no-progress", True, _isotropic_no_progress),
    *(Case(f"friction.slope-{which}", True, lambda which=which: _slope(which)) for which in SLIDES),
    Case("friction.slope-holds", True, _slope_holds),
]
