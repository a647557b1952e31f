"""The figures and studies of docs/media.md ("Granular media"):

- docs/figures/media-alpha.png: Li et al.'s alpha_x and alpha_z over (beta, gamma), as their Fig. 2,
  from snakesim.media.rft_alpha (the simulator's own law);
- docs/figures/media-efficiency.png: the robot sandfish's wave efficiency against A/lambda beside
  Maladen et al.'s peak near 0.2 and measured 0.34;
- printed: a plain drop test (a box dropped into the sand: its depth and vertical speed), the element
  size and `elastic` studies (efficiency and the resting depth against each), the cube snake and
  yaw-pitch-16 on the sand's surface, and why the robot sandfish advances on rigid ground (its
  frequency, heading and contacts, beside a quasi-static Coulomb model of the same wave written here).

    .venv/bin/python scripts/media_figures.py
"""

from __future__ import annotations

import math
import re
import tempfile
from collections.abc import Callable
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from snakesim.media import rft_alpha  # noqa: E402
from snakesim.validation import sand  # noqa: E402
from snakesim.validation.simulate import RATE, ROBOTS, robot_gait_targets, run  # noqa: E402

FIGURES = Path(__file__).resolve().parents[1] / "docs" / "figures"


def alpha_maps() -> None:
    b, g = np.meshgrid(np.linspace(-90, 90, 181), np.linspace(-90, 90, 181))
    ax, az = rft_alpha(np.radians(b), np.radians(g))
    fig, axes = plt.subplots(1, 2, figsize=(9, 4), constrained_layout=True)
    for axis, values, name in zip(axes, (az, ax), ("alpha_z", "alpha_x")):
        image = axis.pcolormesh(b, g, values, cmap="RdBu_r", vmin=-1, vmax=1, shading="auto")
        axis.set_xlabel("beta (degrees)")
        axis.set_ylabel("gamma (degrees)")
        axis.set_title(f"{name} (generic; times zeta)")
        fig.colorbar(image, ax=axis)
    fig.savefig(FIGURES / "media-alpha.png", dpi=80)


def efficiency_figure() -> list[tuple[float, float]]:
    sweep = sand.efficiency_sweep()
    fig, axis = plt.subplots(figsize=(5, 3.5), constrained_layout=True)
    label = "snakesim (RFT), robot sandfish, 1 Hz"
    axis.plot([a for a, _ in sweep], [e for _, e in sweep], "o-", label=label)
    axis.axvline(0.2, color="grey", ls="--", label="Maladen et al.: peak near A/lambda 0.2")
    axis.axhline(0.34, color="k", ls=":", label="measured 0.34 +- 0.02 (A/lambda 0.2)")
    axis.set_xlabel("A / lambda")
    axis.set_ylabel("wave efficiency")
    axis.legend(fontsize=7)
    fig.savefig(FIGURES / "media-efficiency.png", dpi=80)
    return sweep


def world(text: str) -> Path:
    folder = Path(tempfile.mkdtemp())
    path = folder / "world.yaml"
    path.write_text(text)
    return path


def drop_test(extra: str = "") -> tuple[float, float, float]:
    """The robot sandfish held straight (zero targets) dropped from 5 cm above the sand: its depth
    after 2 s, its largest vertical speed in the last second, and its largest height swing there."""
    text = sand.SAND.replace("friction: 0.2}", f"friction: 0.2{extra}}}")
    targets = np.zeros((int(2 * RATE), 6))
    base = run(ROBOTS / "sandfish-robot.yaml", targets, world(text), (0.0, 0.0, 0.165, 0.0))
    z = base[:, 2]
    last = z[int(RATE) :]
    speed = np.abs(np.diff(last)).max() * RATE
    return 0.1 - z[-1], speed, last.max() - last.min()


def study() -> None:
    print("drop test (surface 0.1 m; depth of the centre after 2 s, m; last second: max |vz| m/s, swing m)")
    for elastic in (0.0005, 0.001, 0.002, 0.004):
        d, v, s = drop_test(f", elastic: {elastic}")
        print(f"  elastic {elastic}: depth {d:.4f}, max |vz| {v:.2e}, swing {s:.2e}")
    print("wave efficiency at A/lambda 0.2, 1 Hz, against the element size and elastic")
    for element in (0.02, 0.01, 0.005):
        text = sand.SAND.replace("friction: 0.2}", f"friction: 0.2, element: {element}}}")
        forward, wave = sand._sandfish_speed(text, 0.2, 1.0)
        print(f"  element {element}: efficiency {forward / wave:.4f}")
    for elastic in (0.0005, 0.001, 0.002, 0.004):
        text = sand.SAND.replace("friction: 0.2}", f"friction: 0.2, elastic: {elastic}}}")
        forward, wave = sand._sandfish_speed(text, 0.2, 1.0)
        print(f"  elastic {elastic}: efficiency {forward / wave:.4f}")
    for zeta in (1e5, 2e5, 1e6):
        text = sand.SAND.replace("zeta: 2.0e5", f"zeta: {zeta}")
        forward, wave = sand._sandfish_speed(text, 0.2, 1.0)
        print(f"  zeta {zeta:g}: efficiency {forward / wave:.4f}")
    for mu in (0.0, 0.1, 0.2, 0.4):
        text = sand.SAND.replace("friction: 0.2", f"friction: {mu}")
        forward, wave = sand._sandfish_speed(text, 0.2, 1.0)
        print(f"  friction {mu}: efficiency {forward / wave:.4f}")


def on_the_surface() -> None:
    """yaw-pitch-16 with its own gait on the sand (surface at the plane's height) and on the plane."""
    sand_world = Path(__file__).resolve().parents[1] / "worlds" / "sand.yaml"
    robot = ROBOTS / "yaw-pitch-16.yaml"
    targets = robot_gait_targets(robot, 10.0)
    for name, w in (("sand", sand_world), ("rigid plane, friction 0.3", world("ground_friction: 0.3\n"))):
        base = run(robot, targets, w)
        d = base[-1, :2] - base[0, :2]
        moved = f"{np.hypot(*d):.3f} m ({d[0]:+.3f}, {d[1]:+.3f})"
        print(f"yaw-pitch-16, its gait, 10 s on {name}: moved {moved}")


#: Each segment's collision shapes as a function of the segment's centre (x in its link's frame): the
#: candidates of the study below, beside robots/sandfish-robot.urdf's seven coaxial slices.
RADIUS, HALF = 0.0175, 0.0325
AXIS = 'rpy="0 1.5707963267948966 0"'


def cylinder_slices(n: int) -> Callable[[float], str]:
    """The segment's cylinder (0.065 m, radius 0.0175 m) as ``n`` coaxial slices end to end."""
    length = 2 * HALF / n
    return lambda c: "".join(
        f'<collision><origin xyz="{c - HALF + (k + 0.5) * length:.10g} 0 0" {AXIS}/>'
        f'<geometry><cylinder radius="{RADIUS}" length="{length:.10g}"/></geometry></collision>'
        for k in range(n)
    )


def capsule(overall: float) -> Callable[[float], str]:
    """A capsule of the segment's radius, ``overall`` metres end to end (URDF's length: the cylinder part)."""
    return lambda c: (
        f'<collision><origin xyz="{c} 0 0" {AXIS}/><geometry><capsule radius="{RADIUS}" '
        f'length="{overall - 2 * RADIUS:.10g}"/></geometry></collision>'
    )


def spheres(n: int) -> Callable[[float], str]:
    """``n`` spheres of the segment's radius along it, the end ones touching its ends."""
    return lambda c: "".join(
        f'<collision><origin xyz="{c + o:.5f} 0 0"/><geometry><sphere radius="{RADIUS}"/></geometry>'
        "</collision>"
        for o in np.linspace(-HALF + RADIUS, HALF - RADIUS, n)
    )


def robot_variant(contact: str = "", collision: Callable[[float], str] | None = None) -> Path:
    """The robot sandfish with a <contact> element on every link (pybullet's soft contact, say) and/or
    each segment's collision shapes replaced by ``collision`` of its centre."""
    text = (ROBOTS / "sandfish-robot.urdf").read_text()
    if contact:
        text = re.sub(r'(<link name="seg\d">)', r"\1" + contact, text)
    if collision:
        text = re.sub(r"\s*<collision>.*?</collision>", "", text)
        visual = r'(<visual><origin xyz="([-0-9.]+) 0 0"[^>]*/>.*?</visual>)'
        text = re.sub(visual, lambda m: m.group(1) + collision(float(m.group(2))), text)
    folder = Path(tempfile.mkdtemp())
    (folder / "sandfish-robot.urdf").write_text(text)
    robot = folder / "sandfish-robot.yaml"
    robot.write_text((ROBOTS / "sandfish-robot.yaml").read_text())
    return robot


def sand_efficiency(robot: Path, frequency: float) -> float:
    """The wave efficiency of the sand cases (A/lambda 0.2, 8 cm deep) for another robot file."""
    shipped, sand.ROBOTS = sand.ROBOTS, robot.parent
    try:
        forward, wave = sand._sandfish_speed(sand.SAND, 0.2, frequency)
    finally:
        sand.ROBOTS = shipped
    return forward / wave


def quasi_static_coulomb(points: str, frequency: float = 0.5, cycles: int = 3) -> float:
    """The robot sandfish's wave on isotropic Coulomb friction without inertia (Hu et al. 2009's model
    with equal coefficients): at every step the body's rigid motion (vx, vy, w) is the one whose
    friction forces and moment sum to zero, i.e. the minimum of the dissipation sum |v_i| (convex;
    Newton on |v| smoothed by 1e-6 m/s). ``points``: "line" (10 points a segment) or "ends" (the
    segments' ends, where Bullet puts a cylinder's contact). Returns the centre of mass's advance per
    cycle along the start axis, body lengths, over the last cycle."""
    seg, body = sand.SEGMENT, sand.BODY
    robot = ROBOTS / "sandfish-robot.yaml"
    wave = sand.sandfish_targets(robot, 0.2 * body, body, frequency, seg, cycles / frequency)
    along = (np.arange(10) + 0.5) / 10 - 0.5 if points == "line" else np.array([-0.5, 0.5])

    def shape(joints: np.ndarray) -> np.ndarray:  # in the head's frame, the head's centre at 0
        heading = np.concatenate([[0.0], np.cumsum(joints)])
        centres = sand.segment_centres(np.array([[0, 0, 0, 0, 0, 0, 1.0]]), joints[None, :])[0]
        d = np.stack([np.cos(heading), np.sin(heading)], axis=1)
        return (centres[:, None, :] + along[None, :, None] * seg * d[:, None, :]).reshape(-1, 2)

    dt, eps = 1.0 / RATE, 1e-6
    pose, x, mass = np.zeros(3), np.zeros(3), []
    shapes = [shape(t) for t in wave]
    for k in range(len(wave) - 1):
        p, u = shapes[k], (shapes[k + 1] - shapes[k]) / dt
        a = np.zeros((len(p), 2, 3))
        a[:, 0, 0], a[:, 1, 1], a[:, 0, 2], a[:, 1, 2] = 1, 1, -p[:, 1], p[:, 0]

        def speeds(x: np.ndarray, a: np.ndarray = a, u: np.ndarray = u) -> np.ndarray:
            return np.einsum("nij,j->ni", a, x) + u

        for _ in range(100):
            v = speeds(x)
            norm = np.sqrt((v**2).sum(1) + eps**2)
            grad = np.einsum("nji,nj->i", a, v / norm[:, None])
            outer = v[:, :, None] * v[:, None, :] / (norm**3)[:, None, None]
            m = np.eye(2)[None] / norm[:, None, None] - outer
            step = np.linalg.solve(np.einsum("nji,njk,nkl->il", a, m, a), grad)
            t, before = 1.0, norm.sum()
            while t > 1e-9 and np.sqrt((speeds(x - t * step) ** 2).sum(1) + eps**2).sum() > before:
                t /= 2
            x = x - t * step
            if np.abs(t * step).max() < 1e-12:
                break
        c, s = math.cos(pose[2]), math.sin(pose[2])
        pose = pose + dt * np.array([c * x[0] - s * x[1], s * x[0] + c * x[1], x[2]])
        com = p.mean(0)
        mass.append(pose[:2] + np.array([c * com[0] - s * com[1], s * com[0] + c * com[1]]))
    per = int(round(RATE / frequency))
    return float(mass[-1][0] - mass[-1 - per][0]) / body


def rigid_ground() -> None:
    """Why the robot sandfish advanced on rigid flat ground (sand.sandfish-rigid-ground), and the
    segment shapes tried: each one's advance at 0.5, 1 and 1.5 Hz and its wave efficiency in the sand
    at the same frequencies."""
    print("robot sandfish on rigid ground: centre of mass's advance along the body's axis, lengths/cycle")
    for f in (0.25, 0.5, 1.0, 1.5):
        print(f"  {f} Hz: {sand.rigid_ground_advance(f).mean():+.4f}")
    print("  started at a heading of 0, 15, 30, 45, 60, 90 degrees:")
    for f in (0.5, 1.0, 1.5):
        row = (sand.rigid_ground_advance(f, yaw=math.radians(yaw)).mean() for yaw in (0, 15, 30, 45, 60, 90))
        print(f"    {f} Hz: " + " ".join(f"{a:+.4f}" for a in row))
    for mu in (0.1, 1.0):
        w = f"ground_friction: {mu}\n"
        print(f"  1 Hz, ground_friction {mu}: {sand.rigid_ground_advance(1.0, world_text=w).mean():+.4f}")
    soft = "<contact><stiffness value='10000'/><damping value='20'/></contact>"
    soft_name = "soft contacts (stiffness 1e4 N/m, damping 20)"
    anchor = "<contact><friction_anchor/></contact>"
    print("segment shapes: rigid ground at 0.5, 1, 1.5 Hz | wave efficiency in the sand at 0.5, 1, 1.5 Hz")
    for name, robot in (
        ("one cylinder (before)", robot_variant(collision=cylinder_slices(1))),
        (f"one cylinder, {soft_name}", robot_variant(soft, cylinder_slices(1))),
        ("capsule, 0.065 m end to end", robot_variant(collision=capsule(0.065))),
        ("capsule, 0.1 m end to end (its ends inside the neighbours)", robot_variant(collision=capsule(0.1))),
        ("9 spheres", robot_variant(collision=spheres(9))),
        *((f"{n} slices", robot_variant(collision=cylinder_slices(n))) for n in (2, 3, 5, 7, 9)),
        (f"7 slices, {soft_name}", robot_variant(soft, cylinder_slices(7))),
        ("7 slices, friction anchors", robot_variant(anchor, cylinder_slices(7))),
    ):
        rigid = " ".join(f"{sand.rigid_ground_advance(f, robot).mean():+.4f}" for f in (0.5, 1.0, 1.5))
        eta = " ".join(f"{sand_efficiency(robot, f):.4f}" for f in (0.5, 1.0, 1.5))
        print(f"  {name}: {rigid} | {eta}")
    for points in ("line", "ends"):
        advance = quasi_static_coulomb(points)
        print(f"  quasi-static isotropic Coulomb, contact on the {points}, 0.5 Hz: {advance:+.4f}")


def main() -> None:
    FIGURES.mkdir(parents=True, exist_ok=True)
    alpha_maps()
    sweep = efficiency_figure()
    print("efficiency against A/lambda:", ", ".join(f"{a:g}: {e:.4f}" for a, e in sweep))
    study()
    on_the_surface()
    rigid_ground()


if __name__ == "__main__":
    main()
