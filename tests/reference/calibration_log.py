"""A logged run for `snakesim calibrate`, made by pybullet 3.2.7 with physics the fit is not told.

Writes the joint targets (snake-cli run --targets format: header step,<joint names>) and the trajectory
pybullet produces from them (snake-cli run --output format: step,t,base_x,base_y,base_z,base_qx,base_qy,
base_qz,base_qw,q0..q{M-1}), for a URDF robot on a plane whose lateral friction is changed, driven with
setJointMotorControl2(POSITION_CONTROL, force=<URDF effort>, positionGain=kp, velocityGain=kd,
maxVelocity=v) on every movable joint, as snakesim drives a robot file with `motors: {kp, kd,
max_velocity}`.

Usage:
    python calibration_log.py OUT_DIR [--urdf robots/yaw-pitch-16.urdf | --cylinders 9] [--start 0,0,0.0254,0]
        [--seconds 8] [--kp 0.3] [--kd 0.6] [--max-velocity 4.0] [--ground-friction 0.8]
        [--targets square|smooth|FILE.csv] [--seed 0] [--velocities]

Targets (``--targets``):

- ``square`` (the default): a square wave travelling along the body (each joint switches between +A and
  -A every half period, delayed along the chain) plus a slow offset: steps of 2A that drive every motor
  to its velocity limit, and a body that slides and turns on the ground, so the ground's friction shows.
- ``smooth``: smooth random targets, what a user might log without designing anything: every joint
  follows its own random knots (uniform in +-0.7 rad, one every 0.4 s, from ``--seed``), joined by
  cosine interpolation (no steps).
- a CSV file (``step,<joint names>``, as ``snake-cli run --targets`` reads): those targets (a designed
  excitation, ``snakesim calibrate --design-targets``).

``--cylinders N`` writes the robot instead of reading one: ``robot.urdf`` in OUT_DIR, N cylinder modules
(0.071 m long, 0.025 m radius, 0.23 kg) along +x joined by N - 1 revolute joints alternating yaw (about
z) and pitch (about y), +-1.57 rad, effort 7 N m. ``--velocities`` adds the base's world-frame velocity
and the joint velocities to the log (``base_vx,base_vy,base_vz,base_wx,base_wy,base_wz,qd0..``), as
``getBaseVelocity`` and ``getJointStates`` give them. This file is independent of snakesim: it is what a
pybullet script does with the same robot.
"""

import argparse
import csv
import math
import os
import random

import pybullet as p
from pybullet_utils import bullet_client

DT = 1.0 / 240.0


def targets_for(names, steps, amplitude=0.6, period=1.5):
    """Row k (from 0): the targets before physics step k + 1."""
    rows = []
    m = len(names)
    for k in range(steps):
        t = k * DT
        row = []
        for j in range(m):
            phase = (t / period - j / max(m, 1)) % 1.0
            square = amplitude if phase < 0.5 else -amplitude
            row.append(square + 0.2 * math.sin(2 * math.pi * t / 4.0))
        rows.append(row)
    return rows


def smooth_targets(names, steps, seed, amplitude=0.7, knot_seconds=0.4):
    """Row k (from 0): each joint's cosine interpolation between random knots (uniform in
    +-amplitude, one every knot_seconds, the first at 0 rad so the robot starts at rest)."""
    rng = random.Random(seed)
    knots_needed = int(steps * DT / knot_seconds) + 2
    knots = [[0.0] + [rng.uniform(-amplitude, amplitude) for _ in range(knots_needed)] for _ in names]
    rows = []
    for k in range(steps):
        u = k * DT / knot_seconds
        i = int(u)
        w = (1 - math.cos(math.pi * (u - i))) / 2
        rows.append([(1 - w) * kn[i] + w * kn[i + 1] for kn in knots])
    return rows


def read_targets(path, names):
    """A targets CSV (step,<joint names>) as rows in the robot's joint order."""
    with open(path) as f:
        reader = csv.reader(f)
        header = next(reader)
        order = [header.index(n) for n in names]
        return [[float(r[i]) for i in order] for r in reader if r]


def cylinders_urdf(n, length=0.071, radius=0.025, mass=0.23, effort=7.0):
    """N cylinder modules along +x, joints alternating yaw (z) and pitch (y)."""
    ixx = mass * radius**2 / 2
    iyy = mass * (3 * radius**2 + length**2) / 12
    shape = (
        f'<origin rpy="0 1.5707963267948966 0"/><geometry><cylinder radius="{radius!r}" '
        f'length="{length!r}"/></geometry>'
    )
    lines = ['<?xml version="1.0"?>', f'<robot name="cylinders-{n}">']
    for i in range(n):
        lines += [
            f'  <link name="module{i}">',
            f'    <inertial><mass value="{mass!r}"/><inertia ixx="{ixx!r}" ixy="0" ixz="0" iyy="{iyy!r}" '
            f'iyz="0" izz="{iyy!r}"/></inertial>',
            f"    <visual>{shape}</visual>",
            f"    <collision>{shape}</collision>",
            "  </link>",
        ]
    for i in range(1, n):
        axis = "0 0 1" if i % 2 else "0 1 0"
        lines += [
            f'  <joint name="{"yaw" if i % 2 else "pitch"}{i}" type="revolute">',
            f'    <parent link="module{i - 1}"/><child link="module{i}"/>',
            f'    <origin xyz="{length!r} 0 0"/><axis xyz="{axis}"/>',
            f'    <limit lower="-1.57" upper="1.57" effort="{effort!r}" velocity="10"/>',
            "  </joint>",
        ]
    return "\n".join([*lines, "</robot>", ""])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir")
    here = os.path.dirname(os.path.abspath(__file__))
    parser.add_argument("--urdf", default=os.path.join(here, "..", "..", "robots", "yaw-pitch-16.urdf"))
    parser.add_argument("--start", default="0,0,0.0254,0")
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--kp", type=float, default=0.3)
    parser.add_argument("--kd", type=float, default=0.6)
    parser.add_argument("--max-velocity", type=float, default=4.0)
    parser.add_argument("--ground-friction", type=float, default=0.8)
    parser.add_argument("--cylinders", type=int, help="write and use a robot of N cylinder modules")
    parser.add_argument("--targets", default="square", help="square, smooth or a targets CSV")
    parser.add_argument("--seed", type=int, default=0, help="the smooth targets' random knots")
    parser.add_argument("--velocities", action="store_true", help="log the base and joint velocities")
    args = parser.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    if args.cylinders:
        args.urdf = os.path.join(args.out_dir, "robot.urdf")
        with open(args.urdf, "w") as f:
            f.write(cylinders_urdf(args.cylinders))
    x, y, z, yaw = (float(v) for v in args.start.split(","))
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    try:
        plane = client.createMultiBody(0, client.createCollisionShape(p.GEOM_PLANE))
        # A world file's ground_friction: changeDynamics on the plane before the robot is loaded.
        client.changeDynamics(plane, -1, lateralFriction=args.ground_friction)
        robot = client.loadURDF(args.urdf, [x, y, z], client.getQuaternionFromEuler([0, 0, yaw]))
        client.setGravity(0, 0, -9.81)
        movable, forces, names = [], [], []
        for j in range(client.getNumJoints(robot)):
            info = client.getJointInfo(robot, j)
            if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
                movable.append(j)
                forces.append(info[10])
                names.append(info[1].decode())
        steps = round(args.seconds / DT)
        if args.targets == "square":
            rows = targets_for(names, steps)
        elif args.targets == "smooth":
            rows = smooth_targets(names, steps, args.seed)
        else:
            rows = read_targets(args.targets, names)[:steps]
            steps = len(rows)
        with open(os.path.join(args.out_dir, "targets.csv"), "w") as f:
            f.write(",".join(["step", *names]) + "\n")
            for k, row in enumerate(rows, start=1):
                f.write(",".join([str(k), *(repr(v) for v in row)]) + "\n")
        header = ["step", "t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw"]
        header += [f"q{j}" for j in range(len(movable))]
        if args.velocities:
            header += ["base_vx", "base_vy", "base_vz", "base_wx", "base_wy", "base_wz"]
            header += [f"qd{j}" for j in range(len(movable))]
        with open(os.path.join(args.out_dir, "log.csv"), "w") as f:
            f.write(",".join(header) + "\n")
            for step, row in enumerate(rows, start=1):
                for j, target, force in zip(movable, row, forces):
                    client.setJointMotorControl2(
                        robot,
                        j,
                        p.POSITION_CONTROL,
                        targetPosition=target,
                        force=force,
                        positionGain=args.kp,
                        velocityGain=args.kd,
                        maxVelocity=args.max_velocity,
                    )
                client.stepSimulation()
                pos, orn = client.getBasePositionAndOrientation(robot)
                states = client.getJointStates(robot, movable)
                values = [*pos, *orn, *(s[0] for s in states)]
                if args.velocities:
                    linear, angular = client.getBaseVelocity(robot)
                    values += [*linear, *angular, *(s[1] for s in states)]
                f.write(",".join([str(step), repr(step * DT), *(repr(v) for v in values)]) + "\n")
    finally:
        client.disconnect()


if __name__ == "__main__":
    main()
