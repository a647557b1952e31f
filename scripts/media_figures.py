"""The figures and studies of docs/media.md ("Granular media"):

- docs/figures/media-alpha.png: Li et al.'s alpha_x and alpha_z over (beta, gamma), as their Fig. 2,
  from snakesim.media.rft_alpha (the simulator's own law);
- docs/figures/media-efficiency.png: the robot sandfish's wave efficiency against A/lambda beside
  Maladen et al.'s peak near 0.2 and measured 0.34;
- printed: a plain drop test (a box dropped into the sand: its depth and vertical speed), the element
  size and `elastic` studies (efficiency and the resting depth against each), the cube snake and
  yaw-pitch-16 on the sand's surface, and why the robot sandfish advances on rigid ground (its
  frequency, heading and contacts, beside a quasi-static Coulomb model of the same wave written here;
  Bullet's contacts read through pybullet 3.2.7, which the script needs for that part: the weight's split
  along the body, the friction against the slip; then the suit's soft contact with isotropic friction).

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


#: The suit as the robot file carries it (robots/sandfish-robot.urdf's <contact> on every link, the
#: .yaml's isotropic skin friction), read from the files: the study adds them to the plain robot.
SUIT_CONTACT = re.search(r"<contact>.*?</contact>", (ROBOTS / "sandfish-robot.urdf").read_text()).group(0)
ISOTROPIC_SKIN = re.search(r"(?m)^skin_friction:.*\n", (ROBOTS / "sandfish-robot.yaml").read_text()).group(0)


def robot_variant(contact: str = "", collision: Callable[[float], str] | None = None) -> Path:
    """The PLAIN robot sandfish, the study's "before": the robot file without the suit (its <contact>
    elements and skin friction stripped, so pybullet's defaults: Bullet's rigid contacts and its friction
    cone), with a <contact> element on every link (pybullet's soft contact, say) and/or each segment's
    collision shapes replaced by ``collision`` of its centre. ``robot_variant()`` is the plain robot."""
    text = re.sub(r"\s*<contact>.*?</contact>", "", (ROBOTS / "sandfish-robot.urdf").read_text())
    if contact:
        text = re.sub(r'(<link name="seg\d">)', r"\1" + contact, text)
    if collision:
        text = re.sub(r"\s*<collision>.*?</collision>", "", text)
        visual = r'(<visual><origin xyz="([-0-9.]+) 0 0"[^>]*/>.*?</visual>)'
        text = re.sub(visual, lambda m: m.group(1) + collision(float(m.group(2))), text)
    folder = Path(tempfile.mkdtemp())
    (folder / "sandfish-robot.urdf").write_text(text)
    robot = folder / "sandfish-robot.yaml"
    robot.write_text((ROBOTS / "sandfish-robot.yaml").read_text().replace(ISOTROPIC_SKIN, ""))
    return robot


def sand_efficiency(robot: Path, frequency: float) -> float:
    """The wave efficiency of the sand cases (A/lambda 0.2, 8 cm deep) for another robot file."""
    shipped, sand.ROBOTS = sand.ROBOTS, robot.parent
    try:
        forward, wave = sand._sandfish_speed(sand.SAND, 0.2, frequency)
    finally:
        sand.ROBOTS = shipped
    return forward / wave


def quasi_static_coulomb(
    points: str, frequency: float = 0.5, cycles: int = 3, joints: np.ndarray | None = None
) -> float:
    """The robot sandfish's wave on isotropic Coulomb friction without inertia (Hu et al. 2009's model
    with equal coefficients): at every step the body's rigid motion (vx, vy, w) is the one whose
    friction forces and moment sum to zero, i.e. the minimum of the dissipation sum |v_i| (convex;
    Newton on |v| smoothed by 1e-6 m/s). ``points``: "line" (10 points a segment) or "ends" (the
    segments' ends, where Bullet puts a cylinder's contact). Returns the centre of mass's advance per
    cycle along the start axis, body lengths, over the last cycle. ``joints``: joint angles (steps, 6)
    to use in place of the wave's targets (a run's measured ones)."""
    seg, body = sand.SEGMENT, sand.BODY
    robot = ROBOTS / "sandfish-robot.yaml"
    wave = sand.sandfish_targets(robot, 0.2 * body, body, frequency, seg, cycles / frequency)
    wave = wave if joints is None else joints
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
    """Why the robot sandfish advanced on rigid flat ground (sand.sandfish-rigid-ground-*), and the
    segment shapes tried: each one's advance at 0.5, 1 and 1.5 Hz and its wave efficiency in the sand
    at the same frequencies. All on the plain robot (:func:`robot_variant`, without the suit), as the
    study was made before the robot file carried the suit."""
    plain = robot_variant()
    print("the plain robot sandfish (no suit) on rigid ground: the centre of mass's advance along the body's")
    print("axis, body lengths/cycle")
    for f in (0.25, 0.5, 1.0, 1.5):
        print(f"  {f} Hz: {sand.rigid_ground_advance(f, plain).mean():+.4f}")
    print("  started at a heading of 0, 15, 30, 45, 60, 90 degrees:")
    for f in (0.5, 1.0, 1.5):
        row = (
            sand.rigid_ground_advance(f, plain, yaw=math.radians(y)).mean() for y in (0, 15, 30, 45, 60, 90)
        )
        print(f"    {f} Hz: " + " ".join(f"{a:+.4f}" for a in row))
    for mu in (0.1, 1.0):
        w = f"ground_friction: {mu}\n"
        advance = sand.rigid_ground_advance(1.0, plain, world_text=w).mean()
        print(f"  1 Hz, ground_friction {mu}: {advance:+.4f}")
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


def coulomb_rigid_motion(p: np.ndarray, v: np.ndarray, weight: np.ndarray, eps: float = 1e-7) -> np.ndarray:
    """The rigid motion (vx, vy, w) that, added to contact points ``p`` (n, 2) moving at ``v`` (n, 2),
    makes isotropic Coulomb forces of magnitude ``weight`` (n,) (mu N) and their moment sum to zero:
    the minimum of sum weight |v + (vx, vy) + w x p| (convex; Newton on |v| smoothed by ``eps`` m/s)."""
    a = np.zeros((len(p), 2, 3))
    a[:, 0, 0], a[:, 1, 1], a[:, 0, 2], a[:, 1, 2] = 1, 1, -p[:, 1], p[:, 0]

    def cost(x: np.ndarray) -> float:
        return float((weight * np.sqrt(((np.einsum("nij,j->ni", a, x) + v) ** 2).sum(1) + eps**2)).sum())

    x = np.zeros(3)
    for _ in range(100):
        s = np.einsum("nij,j->ni", a, x) + v
        norm = np.sqrt((s**2).sum(1) + eps**2)
        grad = np.einsum("nji,nj->i", a, weight[:, None] * s / norm[:, None])
        outer = s[:, :, None] * s[:, None, :] / (norm**3)[:, None, None]
        m = (np.eye(2)[None] / norm[:, None, None] - outer) * weight[:, None, None]
        step = np.linalg.solve(np.einsum("nji,njk,nkl->il", a, m, a) + 1e-12 * np.eye(3), grad)
        t, before = 1.0, cost(x)
        while t > 1e-12 and cost(x - t * step) > before:
            t /= 2
        x = x - t * step
        if np.abs(t * step).max() < 1e-13:
            break
    return x


def bullet_contacts(frequency: float, urdf: Path, cone: bool = True, yaw: float = 0.0) -> str:
    """sand.rigid_ground_advance's run replayed in pybullet 3.2.7 (the same steps, bit for bit, for the
    robot file's URDF), reading Bullet's contacts in its last three cycles: each segment's normal force
    (least and most over the cycles), the net friction force on the body (its mass times the centre of
    mass's acceleration) beside mu W, the joints' tracking error and :func:`quasi_static_coulomb` with the
    measured joint angles, the friction's angle off the slip (loaded
    contacts sliding faster than 1 mm/s), and the advance beside what isotropic
    quasi-static Coulomb friction gives on Bullet's own contact points and normal forces
    (:func:`coulomb_rigid_motion` at every step, its centre-of-mass velocity added to Bullet's)."""
    import pybullet as p  # the reference environment's (bash scripts/test adds it to .venv)
    from pybullet_utils import bullet_client

    robot = ROBOTS / "sandfish-robot.yaml"
    per, hold, cycles = int(round(RATE / frequency)), int(RATE), 3
    wave = sand.sandfish_targets(
        robot, 0.2 * sand.BODY, sand.BODY, frequency, sand.SEGMENT, (cycles + 1) / frequency
    )
    targets = np.concatenate([np.repeat(wave[:1], hold, axis=0), wave])
    c = bullet_client.BulletClient(connection_mode=p.DIRECT)
    plane = c.createMultiBody(0, c.createCollisionShape(p.GEOM_PLANE))
    c.changeDynamics(plane, -1, lateralFriction=0.3)  # RIGID's ground_friction
    body = c.loadURDF(
        str(urdf), [0, 0, 0.0175], c.getQuaternionFromEuler([0, 0, yaw]), flags=p.URDF_USE_INERTIA_FROM_FILE
    )
    c.setGravity(0, 0, -9.81)
    if not cone:
        c.setPhysicsEngineParameter(enableConeFriction=0)
    joints = list(range(c.getNumJoints(body)))
    efforts = [c.getJointInfo(body, j)[10] for j in joints]
    base, q, contacts = [], [], []
    for k, row in enumerate(targets):
        c.setJointMotorControlArray(
            body,
            joints,
            p.POSITION_CONTROL,
            targetPositions=list(row),
            forces=efforts,
            positionGains=[0.5] * len(joints),
            velocityGains=[1.0] * len(joints),
        )
        c.stepSimulation()
        pos, orn = c.getBasePositionAndOrientation(body)
        base.append([*pos, *orn])
        q.append([s[0] for s in c.getJointStates(body, joints)])
        if k < hold + per - 1:
            continue
        points = []
        for cp in c.getContactPoints(bodyA=body):
            link, at = cp[3], np.array(cp[5])
            if link < 0:
                (com, _), (lin, ang) = c.getBasePositionAndOrientation(body), c.getBaseVelocity(body)
            else:
                state = c.getLinkState(body, link, computeLinkVelocity=1)
                com, lin, ang = state[0], state[6], state[7]
            velocity = np.array(lin) + np.cross(ang, at - np.array(com))
            friction = cp[10] * np.array(cp[11]) + cp[12] * np.array(cp[13])
            points.append((link + 1, cp[9], *at[:2], *velocity[:2], *friction[:2], cp[8]))
        contacts.append(np.array(points))
    c.disconnect()
    base, q = np.array(base), np.array(q)
    centres = sand.segment_centres(base, q)
    com = centres.mean(axis=1)
    first = hold + per - 1
    load = np.array([np.bincount(r[:, 0].astype(int), r[:, 1], minlength=7) for r in contacts])
    count = np.array([np.bincount(r[r[:, 1] > 0, 0].astype(int), minlength=7) for r in contacts])
    follows = np.mean([np.corrcoef(load[:, g], count[:, g])[0, 1] for g in range(7) if count[:, g].std() > 0])
    net = np.array([np.hypot(*r[:, 6:8].sum(0)) for r in contacts])
    sliding = np.concatenate([r[(np.hypot(r[:, 4], r[:, 5]) > 1e-3) & (r[:, 1] > 0)] for r in contacts])
    off = np.degrees(
        np.abs(
            np.arctan2(
                sliding[:, 5] * sliding[:, 6] - sliding[:, 4] * sliding[:, 7],
                -(sliding[:, 4] * sliding[:, 6] + sliding[:, 5] * sliding[:, 7]),
            )
        )
    )
    measured = quasi_static_coulomb("line", frequency, joints=q[first : first + 2 * per + 1])
    shift = np.array(
        [
            coulomb_rigid_motion(r[:, 2:4] - com[first + i], r[:, 4:6], r[:, 1])[:2]
            for i, r in enumerate(contacts)
        ]
    )
    bullet, coulomb = [], []
    for n in range(cycles):
        a = first + n * per
        axis = (centres[a : a + per, 0] - centres[a : a + per, -1]).mean(axis=0)
        axis /= np.linalg.norm(axis)
        bullet.append((com[a + per] - com[a]) @ axis / sand.BODY)
        coulomb.append(bullet[-1] + shift[n * per : (n + 1) * per].sum(0) / RATE @ axis / sand.BODY)
    weight = 0.13 * 7 * 9.81
    tracking = np.sqrt(((q[first:] - targets[first:]) ** 2).mean())
    return (
        f"advance {np.mean(bullet):+.4f}, quasi-static Coulomb on Bullet's contacts {np.mean(coulomb):+.4f}; "
        f"segment loads (N, weight {weight / 7:.2f}) least {' '.join(f'{v:.2f}' for v in load.min(0))}, "
        f"most {' '.join(f'{v:.2f}' for v in load.max(0))}; net friction {net.mean():.3f} N "
        f"(mu W {0.15 * weight:.2f}); tracking {tracking:.4f} rad rms, quasi-static Coulomb with these "
        f"joint angles {measured:+.4f}; the friction off the slip (loaded, sliding contacts) by "
        f"{np.median(off):.1f} degrees (median), {np.percentile(off, 90):.1f} (90th percentile); the loaded "
        f"points' mean depth {-1000 * np.concatenate([r[r[:, 1] > 0, 8] for r in contacts]).mean():.4f} mm, "
        f"{count.min()} to {count.max()} of them a segment, a segment's load against their count "
        f"correlated {follows:.2f} (the segments' mean)"
    )


def rigid_ground_causes() -> None:
    """What makes the robot sandfish advance on rigid ground at 0.5 Hz (docs/media.md, "No advance on
    rigid ground", the checks in order): Bullet's friction (cone, pyramid, snakesim's isotropic Coulomb
    skin), the joints' tracking and inertia, the weight's split along the body; then the suit's soft
    contact with isotropic friction (the robot file as shipped) against its stiffness. "Rigid contacts"
    is the plain robot (:func:`robot_variant`); pybullet reads the URDF's <contact> but not the skin."""
    urdf = robot_variant().parent / "sandfish-robot.urdf"
    soft = robot_variant(SUIT_CONTACT)
    print("Bullet's contacts (pybullet 3.2.7, heading 0, rigid contacts unless said):")
    for f in (0.25, 0.5, 1.0, 1.5):
        print(f"  {f} Hz: {bullet_contacts(f, urdf)}")
    print(f"  0.5 Hz, heading 45: {bullet_contacts(0.5, urdf, yaw=math.radians(45))}")
    print(f"  0.5 Hz, pyramid friction: {bullet_contacts(0.5, urdf, cone=False)}")
    for f in (0.25, 0.5):
        print(f"  {f} Hz, the suit's soft contact: {bullet_contacts(f, soft.parent / 'sandfish-robot.urdf')}")
    stiff = robot_variant('<contact><stiffness value="1e5"/><damping value="20"/></contact>')
    print(f"  0.5 Hz, soft contact 1e5 N/m: {bullet_contacts(0.5, stiff.parent / 'sandfish-robot.urdf')}")

    def with_skin(robot: Path) -> Path:
        robot.write_text(robot.read_text() + ISOTROPIC_SKIN)
        return robot

    def row(robot: Path, yaw: float = 0.0) -> str:
        return " ".join(
            f"{sand.rigid_ground_advance(f, robot, yaw=math.radians(yaw)).mean():+.4f}"
            for f in (0.25, 0.5, 1.0, 1.5)
        )

    print("advance at 0.25, 0.5, 1, 1.5 Hz, started at a heading of 0 | of 45 degrees:")
    rows = [
        ("rigid contacts, Bullet's cone (the plain robot)", robot_variant()),
        ("rigid contacts, isotropic skin", with_skin(robot_variant())),
        ("soft contacts (the robot file's), Bullet's cone", soft),
    ]
    for k, d in ((1e3, 20), (3e3, 20), (1e4, 20), (3e4, 20), (1e5, 20), (1e4, 5), (1e4, 50)):
        contact = f'<contact><stiffness value="{k:g}"/><damping value="{d:g}"/></contact>'
        rows.append(
            (f"soft contacts {k:g} N/m, {d:g} N s/m, isotropic skin", with_skin(robot_variant(contact)))
        )
    shipped = "the robot file as shipped (its suit: 1e4 N/m, 20 N s/m, isotropic skin)"
    rows.append((shipped, ROBOTS / "sandfish-robot.yaml"))
    for name, robot in rows:
        print(f"  {name}: {row(robot)} | {row(robot, 45)}")


def main() -> None:
    FIGURES.mkdir(parents=True, exist_ok=True)
    alpha_maps()
    sweep = efficiency_figure()
    print("efficiency against A/lambda:", ", ".join(f"{a:g}: {e:.4f}" for a, e in sweep))
    study()
    on_the_surface()
    rigid_ground()
    rigid_ground_causes()


if __name__ == "__main__":
    main()
