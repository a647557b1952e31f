"""The granular medium (docs/media.md, "Granular media") against its published sources.

- Li, Zhang and Goldman 2013 (Science 339:1408): the generic law's normalisation, ``alpha_z = 1.000`` for
  a horizontal plate pushed straight down, and the plate experiment: the force on a plate equals the law
  integrated over it (the probe's discretisation held to 2 %).
- Maladen, Ding, Umbanhowar and Goldman 2011 (IJRR 30(7):793): the robot sandfish's wave efficiency
  (forward speed over wave speed) 0.34 +- 0.02 below the surface, with speed growing with frequency at
  constant efficiency; no forward motion on a flat rigid surface of isotropic friction; and (Maladen et
  al. 2009, Science 325:314, for the sandfish's wave) efficiency peaking near A/lambda = 0.2.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from snakesim.media import probe, rft_alpha
from snakesim.validation import Case, Result, relative
from snakesim.validation.simulate import RATE, ROBOTS, run, run_with_joints, sandfish_targets, two_halves

LI = "Li, Zhang & Goldman 2013, Science 339:1408"
MALADEN = "Maladen et al. 2011, IJRR 30(7):793"
MALADEN_2009 = "Maladen et al. 2009, Science 325:314"

#: The robot sandfish (robots/sandfish-robot.yaml): 7 segments of 0.065 m (estimated), one wave along it.
SEGMENT = 0.065
SEGMENTS = 7
BODY = SEGMENT * SEGMENTS

#: The glass beads the robot swam in, as this medium is written (zeta and friction estimated; see
#: docs/media.md). The surface stands 0.1 m above the plane so that a start 0.08 m below it is a
#: start at z = 0.02 (a start may not lie below z = 0).
SAND = """ground_friction: 0.3
media:
  - {medium: granular, area: [-3, -3, 3, 3], surface: 0.1, depth: 0.4, zeta: 2.0e5, friction: 0.2}
"""
BURIED = (0.0, 0.0, 0.02, 0.0)
RIGID = "ground_friction: 0.3\n"


def _alpha_z_plate_down() -> Result:
    _, az = rft_alpha(0.0, math.pi / 2)
    value = float(az)
    return Result(
        name="sand.alpha-z-plate-down",
        quantity="alpha_z, horizontal plate moving straight down",
        published=1.0,
        unit="",
        source=f"{LI} (A00 + A10 + B11 + B01 + B-11)",
        simulated=value,
        tolerance="1e-12",
        passed=abs(value - 1.0) <= 1e-12,
    )


def _probe(beta: float, gamma: float) -> Result:
    with tempfile.TemporaryDirectory() as folder:
        world = Path(folder) / "sand.yaml"
        world.write_text(
            "media:\n  - {medium: granular, area: [-1, -1, 1, 1], depth: 0.5, zeta: 2.0e5, "
            "friction: 0.2, element: 0.005}\n"
        )
        r = probe(world, (0.0381, 0.0254), beta, gamma, 0.076)["result"]
    law = math.hypot(r["law_x"], r["law_z"])
    measured = math.hypot(r["force_x"], r["force_z"])
    error = math.hypot(r["force_x"] - r["law_x"], r["force_z"] - r["law_z"]) / law
    return Result(
        name=f"sand.probe-beta{beta:g}-gamma{gamma:g}",
        quantity=f"|force| on a 3.81 x 2.54 cm plate, 7.6 cm deep, beta {beta:g}, gamma {gamma:g} deg",
        published=law,
        unit="N",
        source=f"{LI}, the law integrated over the plate",
        simulated=measured,
        tolerance="2 % (vector difference)",
        passed=error <= 0.02,
    )


#: Two 1 kg half-cubes (0.05 x 0.1 x 0.1 m) joined by a yaw joint held straight: a 10 cm cube of 2 kg.
HALVES = two_halves("halves", (0.05, 0.1, 0.1), 1.0)


def _drop_energy() -> Result:
    """A 2 kg, 10 cm cube released at rest with its bottom on the surface sinks until the law's work
    equals the potential energy it lost (RFT is plastic: no rebound): with the bottom's stress
    zeta d (alpha_z(0, pi/2) = 1) and the sides' zeta alpha_z(pi/2, pi/2) d (0.128; perimeter 0.4 m:
    the halves' touching faces are inside the body and take nothing),
    zeta A d / 2 + zeta 0.128 P d^2 / 6 = m g."""
    zeta, area, perimeter, mass, g = 2.0e5, 0.01, 0.4, 2.0, 9.81
    side = 0.206 - 0.169 - 0.212 + 0.358 - 0.055
    a, b = zeta * side * perimeter / 6.0, zeta * area / 2.0
    published = (-b + math.sqrt(b * b + 4.0 * a * mass * g)) / (2.0 * a)
    with tempfile.TemporaryDirectory() as folder:
        robot = Path(folder) / "halves.urdf"
        robot.write_text(HALVES)
        world = Path(folder) / "sand.yaml"
        world.write_text(
            "media:\n  - {medium: granular, area: [-1, -1, 1, 1], depth: 0.3, zeta: 2.0e5, friction: 0.2, "
            "element: 0.005}\n"
        )
        base = run(robot, np.zeros((720, 1)), world, (0.0, 0.0, 0.05, 0.0))
    simulated = float(0.05 - base[-1, 2])
    return Result(
        name="sand.drop-energy",
        quantity="resting depth of a 2 kg, 10 cm cube released on the surface",
        published=published,
        unit="m",
        source=f"{LI}, the law's work = m g d (energy balance)",
        simulated=simulated,
        tolerance="3 %",
        passed=relative(simulated, published) <= 0.03,
    )


def _sandfish_speed(
    world_text: str, amplitude: float, frequency: float, cycles: int = 4, start=BURIED
) -> tuple[float, float]:
    """Forward speed (m/s) over whole cycles after the first, and the wave speed, of the robot sandfish
    driven by the sine wave of ``amplitude`` (A/lambda) with one wave on the body."""
    wavelength = BODY
    robot = ROBOTS / "sandfish-robot.yaml"
    targets = sandfish_targets(
        robot, amplitude * wavelength, wavelength, frequency, SEGMENT, cycles / frequency
    )
    with tempfile.TemporaryDirectory() as folder:
        world = Path(folder) / "world.yaml"
        world.write_text(world_text)
        base = run(robot, targets, world, start)
    first = int(round(RATE / frequency))
    seconds = (len(base) - 1 - first) / RATE
    forward = (base[-1, 0] - base[first, 0]) / seconds
    return float(forward), wavelength * frequency


def _efficiency(frequency: float) -> Result:
    forward, wave = _sandfish_speed(SAND, 0.2, frequency)
    eta = forward / wave
    return Result(
        name=f"sand.sandfish-efficiency-{frequency:g}hz",
        quantity=f"wave efficiency below the surface, A/lambda 0.2, {frequency:g} Hz",
        published=0.34,
        unit="",
        source=f"{MALADEN} (0.34 +- 0.02)",
        simulated=eta,
        tolerance="15 %",
        passed=relative(eta, 0.34) <= 0.15,
    )


def segment_centres(base: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """The centres of the robot sandfish's seven segments in the ground plane, (steps, 7, 2), from its
    head's pose and its six yaw joints' angles (the chain of robots/sandfish-robot.urdf: the head's
    centre is the base, each joint at the end of a segment, the body along -x). The body on flat ground
    stays level (yaw joints only), so the plane is its frame."""
    x, y, z, w = base[:, 3], base[:, 4], base[:, 5], base[:, 6]
    heading = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    angles = heading[:, None] + np.concatenate([np.zeros((len(base), 1)), np.cumsum(joints, axis=1)], axis=1)
    back = -np.stack([np.cos(angles), np.sin(angles)], axis=2)  # unit vectors towards the tail
    centres = np.empty((len(base), SEGMENTS, 2))
    centres[:, 0] = base[:, :2]
    joint = base[:, :2] + back[:, 0] * SEGMENT / 2
    for i in range(1, SEGMENTS):
        centres[:, i] = joint + back[:, i] * SEGMENT / 2
        joint = joint + back[:, i] * SEGMENT
    return centres


def advance_per_cycle(centres: np.ndarray, first: int, per: int) -> np.ndarray:
    """The centre of mass's advance in body lengths over each whole cycle from step ``first`` (cycles of
    ``per`` steps), along the body's mean axis in that cycle (the mean of tail-to-head over the cycle):
    what "moves forward" means for an undulating body, whose head swings and whose heading oscillates."""
    mass = centres.mean(axis=1)  # equal segments
    out = []
    for a in range(first, len(centres) - per, per):
        axis = (centres[a : a + per, 0] - centres[a : a + per, -1]).mean(axis=0)
        out.append(float((mass[a + per] - mass[a]) @ axis / np.linalg.norm(axis)) / BODY)
    return np.array(out)


def rigid_ground_advance(
    frequency: float = 1.0,
    robot: Path | None = None,
    world_text: str = RIGID,
    cycles: int = 4,
    yaw: float = 0.0,
) -> np.ndarray:
    """The robot sandfish on rigid flat ground: held for a second in the wave's first shape (it settles
    there: the snap into shape turns it), one cycle of the wave to settle into its motion, then
    ``cycles`` whole cycles, each one's advance (:func:`advance_per_cycle`). The robot file carries the
    suit's soft contact and isotropic friction (robots/sandfish-robot.urdf and .yaml; docs/media.md, "No
    advance on rigid ground"): the cases run it as shipped."""
    robot = robot or ROBOTS / "sandfish-robot.yaml"
    wave = sandfish_targets(robot, 0.2 * BODY, BODY, frequency, SEGMENT, (cycles + 1) / frequency)
    hold = int(RATE)
    targets = np.concatenate([np.repeat(wave[:1], hold, axis=0), wave])
    with tempfile.TemporaryDirectory() as folder:
        world = Path(folder) / "world.yaml"
        world.write_text(world_text)
        base, joints = run_with_joints(robot, targets, world, (0.0, 0.0, 0.0175, yaw))
    per = int(round(RATE / frequency))
    return advance_per_cycle(segment_centres(base, joints), hold + per - 1, per)


def _rigid_no_advance(frequency: float) -> Result:
    advance = float(rigid_ground_advance(frequency).mean())
    return Result(
        name=f"sand.sandfish-rigid-ground-{frequency:g}hz",
        quantity=(
            "advance of the centre of mass along the body's axis, rigid flat ground, friction 0.3, "
            f"{frequency:g} Hz (the robot file's suit: soft contact, isotropic Coulomb friction)"
        ),
        published=0.0,
        unit="body lengths/cycle",
        source=f"{MALADEN} (no forward motion on a rigid flat surface, for the isotropy of friction)",
        simulated=advance,
        tolerance="< 0.02 body lengths per cycle",
        passed=abs(advance) < 0.02,
    )


#: A/lambda of the efficiency sweep.
AMPLITUDES = (0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4)


def efficiency_sweep() -> list[tuple[float, float]]:
    """(A/lambda, wave efficiency) of the robot sandfish below the surface at 1 Hz."""
    out = []
    for a in AMPLITUDES:
        forward, wave = _sandfish_speed(SAND, a, 1.0)
        out.append((a, forward / wave))
    return out


def _efficiency_peak() -> Result:
    sweep = efficiency_sweep()
    peak = max(sweep, key=lambda p: p[1])[0]
    return Result(
        name="sand.efficiency-peak-amplitude",
        quantity="A/lambda of the highest wave efficiency (0.05 to 0.4, 1 Hz)",
        published=0.2,
        unit="",
        source=f"{MALADEN_2009}; {MALADEN}",
        simulated=peak,
        tolerance="within 0.05",
        passed=abs(peak - 0.2) <= 0.05 + 1e-9,
    )


CASES = [
    Case("sand.alpha-z-plate-down", True, _alpha_z_plate_down),
    Case("sand.drop-energy", True, _drop_energy),
    *(
        Case(f"sand.probe-beta{b:g}-gamma{g:g}", True, lambda b=b, g=g: _probe(b, g))
        for b, g in ((0.0, 90.0), (30.0, 45.0), (-45.0, 20.0), (90.0, 0.0))
    ),
    *(Case(f"sand.sandfish-efficiency-{f:g}hz", True, lambda f=f: _efficiency(f)) for f in (0.5, 1.0, 1.5)),
    *(
        Case(f"sand.sandfish-rigid-ground-{f:g}hz", True, lambda f=f: _rigid_no_advance(f))
        for f in (0.5, 1.0, 1.5)
    ),
    Case("sand.efficiency-peak-amplitude", False, _efficiency_peak),
]
