"""Water's validation cases (issue 60, docs/media.md "Water"): still water against Archimedes and the drag
law, and Mamba's forward speeds against Kelasidi et al.'s measurements.

Every case builds its robot and world files in a temporary directory (small bodies written here, in
the same URDF and YAML the robots/ and worlds/ files use), drives the robot with joint targets through
``snakesim._core.simulate_robot`` (snake-core's ``run_targets``, as ``snake-cli run --targets``) and
compares one number with its published value.

Sources:

- Archimedes' principle: a floating body displaces its own weight of water, so a box of mass ``m`` and
  footprint ``A`` floats at the draft ``m / (rho A)``; a body of the water's density stays where it is.
- Kelasidi et al.'s drag law (IEEE Robotics & Automation Magazine 23(1), March 2016, eqs. 7-8, with the
  Morison-type coefficients of Kelasidi et al., ICRA 2014): a link sinking broadside at ``u`` feels
  ``c_n (u + u^2)`` with ``c_n = 1/2 rho C_D 2a 2l``, so it sinks at the ``u`` where that equals its
  weight less its buoyancy; a passive body in a current reaches the current's velocity.
- Mamba's measured forward speeds (Kelasidi et al. 2016, RAM, the text after eq. 28): 0.1288 m/s for
  lateral undulation and 0.0894 m/s for eel-like motion. The gait parameters of those two runs, and
  Tables 2 and 3 of the paper (the sweeps), could not be retrieved here; the parameters below are
  this project's reading, marked as such in each case's quantity, and the cases are not quick.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from snakesim.validation import Case, Result

DT = 1.0 / 240.0
RHO = 1000.0
G = 9.81
# Kelasidi et al.'s C_D (ICRA 2014; RAM 2016).
C_D = 2.0

ARCHIMEDES = "Archimedes' principle"
DRAG_LAW = "Kelasidi et al. 2016 (IEEE RAM 23(1)), eqs. 7-8, c_n = 1/2 rho C_D 2a 2l"
MAMBA = "Kelasidi et al. 2016 (IEEE RAM 23(1), p. 54): Mamba measured"
ROBOTS = Path(__file__).resolve().parents[4] / "robots"


def _pool(folder: Path, surface: float, depth: float, current: tuple[float, float, float]) -> Path:
    path = folder / "water.yaml"
    path.write_text(
        "media:\n"
        f"  - {{medium: water, area: [-50, -50, 50, 50], surface: {surface}, depth: {depth},\n"
        f"     density: {RHO}, current: [{current[0]}, {current[1]}, {current[2]}]}}\n"
    )
    return path


def _two_link_robot(folder: Path, geometry: str, mass: float, length: float, z: float) -> Path:
    """Two equal links along +y, joined by a yaw joint held straight; each link's shape centred on it."""
    inertia = '<inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/>'
    links = []
    for k in range(2):
        links.append(
            f'  <link name="l{k}">\n'
            f'    <inertial><origin xyz="0 {length / 2} 0"/><mass value="{mass!r}"/>{inertia}</inertial>\n'
            f'    <collision><origin xyz="0 {length / 2} 0" rpy="1.5707963267948966 0 0"/>'
            f"<geometry>{geometry}</geometry></collision>\n"
            "  </link>"
        )
    joint = (
        '  <joint name="j1" type="revolute"><parent link="l0"/><child link="l1"/>'
        f'<origin xyz="0 {length} 0"/><axis xyz="0 0 1"/>'
        '<limit lower="-1.5" upper="1.5" effort="50" velocity="5"/></joint>'
    )
    urdf = folder / "body.urdf"
    urdf.write_text(
        '<?xml version="1.0"?>\n<robot name="body">\n' + "\n".join(links) + "\n" + joint + "\n</robot>\n"
    )
    robot = folder / "body.yaml"
    robot.write_text(f"urdf: body.urdf\nstart: [0, 0, {z}, 0]\ninertia: file\n")
    return robot


def _run(robot: Path, world: Path, seconds: float, targets: np.ndarray | None = None) -> np.ndarray:
    from snakesim import _core

    steps = round(seconds / DT)
    if targets is None:
        joints = len(_core.robot_joint_names(str(robot)))
        targets = np.zeros((steps, joints))
    base, _ = _core.simulate_robot(str(robot), np.ascontiguousarray(targets), str(world))
    return base


def _result(
    name: str, quantity: str, published: float, unit: str, source: str, simulated: float, tol: float
) -> Result:
    passed = abs(simulated - published) <= tol * abs(published)
    return Result(name, quantity, published, unit, source, simulated, f"{tol * 100:g} %", passed)


def floating_box() -> Result:
    """Two 0.2 x 0.2 x 0.1 m boxes (0.4 x 0.2 footprint), 2 kg each: draft m / (rho A) = 0.05 m."""
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        # The boxes' long side (0.2 m) along +y like a robot's body; 0.1 m tall.
        robot = _two_link_robot(folder, '<box size="0.2 0.1 0.2"/>', 2.0, 0.2, 1.02)
        base = _run(robot, _pool(folder, 1.0, 1.0, (0, 0, 0)), 20.0)
    published = 2 * 2.0 / (RHO * 0.4 * 0.2)
    draft = 1.0 - (base[-240:, 2].mean() - 0.05)
    return _result(
        "water.archimedes-floating-box",
        "draft of a floating box, m (0.4 x 0.2 x 0.1 m, 4 kg)",
        published,
        "m",
        ARCHIMEDES + ": m / (rho A)",
        float(draft),
        0.01,
    )


def neutral_body() -> Result:
    """Two cylinders of the water's density, 0.5 m under: under 1 mm in 10 s."""
    r, length = 0.05, 0.2
    mass = RHO * math.pi * r * r * length
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        robot = _two_link_robot(folder, f'<cylinder radius="{r}" length="{length}"/>', mass, length, 0.5)
        base = _run(robot, _pool(folder, 1.0, 1.0, (0, 0, 0)), 10.0)
    moved = float(np.linalg.norm(base[-1, :3] - base[0, :3]))
    return Result(
        "water.archimedes-neutral",
        "drift of a neutrally buoyant body in 10 s, m",
        0.0,
        "m",
        ARCHIMEDES,
        moved,
        "< 1 mm",
        moved < 1e-3,
    )


def current() -> Result:
    """A neutrally buoyant body in a 0.2 m/s current reaches 0.2 m/s."""
    r, length = 0.05, 0.2
    mass = RHO * math.pi * r * r * length
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        robot = _two_link_robot(folder, f'<cylinder radius="{r}" length="{length}"/>', mass, length, 0.5)
        base = _run(robot, _pool(folder, 1.0, 1.0, (0.2, 0, 0)), 30.0)
    speed = (base[-1, 0] - base[-241, 0]) / (240 * DT)
    return _result(
        "water.archimedes-current",
        "speed of a passive body in a 0.2 m/s current, m/s",
        0.2,
        "m/s",
        DRAG_LAW + ": no drag at the current's velocity",
        float(speed),
        0.01,
    )


def terminal_velocity() -> Result:
    """Two cylinders 1.5 times as dense as water sinking broadside: c_n (u + u^2) = (m - rho V) g."""
    r, length = 0.02, 0.3
    volume = math.pi * r * r * length
    mass = 1.5 * RHO * volume
    c_n = 0.5 * RHO * C_D * 2 * r * length
    net = (mass - RHO * volume) * G
    published = (-1.0 + math.sqrt(1.0 + 4.0 * net / c_n)) / 2.0
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        robot = _two_link_robot(folder, f'<cylinder radius="{r}" length="{length}"/>', mass, length, 9.0)
        base = _run(robot, _pool(folder, 10.0, 10.0, (0, 0, 0)), 6.0)
    sinking = -(base[-1, 2] - base[-121, 2]) / (120 * DT)
    return _result(
        "water.archimedes-terminal",
        "sinking speed of a dense link falling broadside, m/s",
        published,
        "m/s",
        DRAG_LAW,
        float(sinking),
        0.01,
    )


def mamba(pattern: str, alpha_deg: float, omega_deg: float, delta_deg: float, measured: float) -> Result:
    """Mamba's forward speed: the head's mean speed over whole gait cycles after 20 s of swimming."""
    from snakesim import _core

    robot = ROBOTS / "mamba-10.yaml"
    world = ROBOTS.parent / "worlds" / "pool.yaml"
    if not (robot.is_file() and world.is_file()):
        # The robot and the pool ship with the repository, not the package.
        raise FileNotFoundError(f"the Mamba cases need the repository's {robot} and {world}")
    omega = math.radians(omega_deg)
    period = 2 * math.pi / omega
    cycles = max(1, math.floor(20.0 / period))
    seconds = 20.0 + cycles * period
    steps = round(seconds / DT)
    targets = _core.swim_targets(
        str(robot), pattern, math.radians(alpha_deg), omega, math.radians(delta_deg), steps
    )
    base = _run(robot, world, seconds, targets)
    window = round(cycles * period / DT)
    a, b = base[-window - 1, :2], base[-1, :2]
    speed = float(np.linalg.norm(b - a) / (window * DT))
    name = f"water.mamba-{pattern}-a{alpha_deg:g}-w{omega_deg:g}-d{delta_deg:g}"
    return _result(
        name,
        f"forward speed, {pattern} alpha {alpha_deg:g} deg, omega {omega_deg:g} deg/s, "
        f"delta {delta_deg:g} deg (parameters not retrieved from the paper: this project's reading)",
        measured,
        "m/s",
        MAMBA,
        speed,
        0.15,
    )


CASES: list[Case] = [
    Case("water.archimedes-floating-box", True, floating_box),
    Case("water.archimedes-neutral", True, neutral_body),
    Case("water.archimedes-current", True, current),
    Case("water.archimedes-terminal", True, terminal_velocity),
    Case("water.mamba-lateral-a30-w70-d40", False, lambda: mamba("lateral", 30, 70, 40, 0.1288)),
    Case("water.mamba-eel-a50-w70-d40", False, lambda: mamba("eel", 50, 70, 40, 0.0894)),
]
