"""A logged run for `snakesim calibrate`, made by pybullet 3.2.7 with physics the fit is not told.

Writes the joint targets (snake-cli run --targets format: header step,<joint names>) and the trajectory
pybullet produces from them (snake-cli run --output format: step,t,base_x,base_y,base_z,base_qx,base_qy,
base_qz,base_qw,q0..q{M-1}), for a URDF robot on a plane whose lateral friction is changed, driven with
setJointMotorControl2(POSITION_CONTROL, force=<URDF effort>, positionGain=kp, velocityGain=kd,
maxVelocity=v) on every movable joint, as snakesim drives a robot file with `motors: {kp, kd,
max_velocity}`.

Usage:
    python calibration_log.py OUT_DIR [--urdf robots/yaw-pitch-16.urdf] [--start 0,0,0.0254,0]
        [--seconds 8] [--kp 0.3] [--kd 0.6] [--max-velocity 4.0] [--ground-friction 0.8]

The targets are a square wave travelling along the body (each joint switches between +A and -A every
half period, delayed along the chain) plus a slow offset: steps of 2A that drive every motor to its
velocity limit, and a body that slides and turns on the ground, so the ground's friction shows. This
file is independent of snakesim: it is what a pybullet script does with the same robot.
"""

import argparse
import math
import os

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
    args = parser.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
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
        rows = targets_for(names, steps)
        with open(os.path.join(args.out_dir, "targets.csv"), "w") as f:
            f.write(",".join(["step", *names]) + "\n")
            for k, row in enumerate(rows, start=1):
                f.write(",".join([str(k), *(repr(v) for v in row)]) + "\n")
        header = ["step", "t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw"]
        header += [f"q{j}" for j in range(len(movable))]
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
                q = [s[0] for s in client.getJointStates(robot, movable)]
                f.write(",".join([str(step), repr(step * DT), *(repr(v) for v in (*pos, *orn, *q))]) + "\n")
    finally:
        client.disconnect()


if __name__ == "__main__":
    main()
