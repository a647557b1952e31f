"""The pybullet 3.2.7 reference for snakesim's URDF parity tests.

Loads a URDF robot as a pybullet user does and drives it with given joint targets, writing one CSV row
per 1/240 s step with the state after that step.

Usage:
    python urdf_reference.py SCENARIOS.json OUT_DIR

SCENARIOS.json is a list of scenarios; each is written to OUT_DIR/<name>.csv. A scenario:
    name        file stem
    urdf        path of the URDF file
    start       [x, y, z, yaw] of the root link frame
    inertia     "shapes" (default flags) or "file" (URDF_USE_INERTIA_FROM_FILE)
    friction    list of [link, [ax, ay, az]]: changeDynamics(anisotropicFriction=...) in that order
    kp, kd      motor gains
    max_velocity  optional: one value per movable joint, a number or null; when given, each step drives
                every movable joint with setJointMotorControl2(..., maxVelocity=v), v left out where null
                (setJointMotorControlArray has no maxVelocity); otherwise one setJointMotorControlArray
    targets     path of a CSV without header: row k holds the targets of every movable joint for step k
The movable joints are the revolute and prismatic ones (continuous joints are revolute in pybullet), in
joint order; each motor's force is the joint's URDF effort as pybullet reports it (getJointInfo).
Columns: step, t, base_x, base_y, base_z, base_qx, base_qy, base_qz, base_qw, q0..q{M-1}, then
vx, vy, vz, wx, wy, wz and qd0..qd{M-1}, tau0..tau{M-1} (motor torques).

This file is independent of snakesim: it is what a pybullet script does with the same robot.
"""

import csv
import json
import os
import sys

import pybullet as p
from pybullet_utils import bullet_client

DT = 1.0 / 240.0


def load(client, scenario):
    """The plane, the robot, gravity and friction as the scenario says; returns the robot, its movable
    joints, their forces (URDF efforts), the gains and the targets."""
    client.createMultiBody(0, client.createCollisionShape(p.GEOM_PLANE))
    x, y, z, yaw = scenario["start"]
    flags = p.URDF_USE_INERTIA_FROM_FILE if scenario.get("inertia") == "file" else 0
    robot = client.loadURDF(
        scenario["urdf"], [x, y, z], client.getQuaternionFromEuler([0, 0, yaw]), flags=flags
    )
    client.setGravity(0, 0, -9.81)
    for link, friction in scenario.get("friction", []):
        client.changeDynamics(robot, link, anisotropicFriction=friction)
    movable = []
    forces = []
    for j in range(client.getNumJoints(robot)):
        info = client.getJointInfo(robot, j)
        if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
            movable.append(j)
            forces.append(info[10])
    kp, kd = scenario.get("kp", 0.1), scenario.get("kd", 1.0)
    with open(scenario["targets"]) as f:
        targets = [[float(v) for v in row] for row in csv.reader(f)]
    return robot, movable, forces, kp, kd, targets


def drive(client, robot, movable, row, forces, kp, kd, max_velocity):
    """Sets one step's position targets: one array call, or with maximum velocities one call per
    joint, as a pybullet user writes each."""
    m = len(movable)
    if max_velocity is None:
        client.setJointMotorControlArray(
            robot,
            movable,
            p.POSITION_CONTROL,
            targetPositions=row,
            forces=forces,
            positionGains=[kp] * m,
            velocityGains=[kd] * m,
        )
        return
    assert len(max_velocity) == m, f"{len(max_velocity)} maximum velocities for {m} movable joints"
    for j, target, force, v in zip(movable, row, forces, max_velocity):
        limit = {} if v is None else {"maxVelocity": v}
        client.setJointMotorControl2(
            robot,
            j,
            p.POSITION_CONTROL,
            targetPosition=target,
            force=force,
            positionGain=kp,
            velocityGain=kd,
            **limit,
        )


def run(scenario, out_path):
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    try:
        robot, movable, forces, kp, kd, targets = load(client, scenario)
        m = len(movable)
        max_velocity = scenario.get("max_velocity")
        header = ["step", "t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw"]
        header += [f"q{j}" for j in range(m)]
        header += ["vx", "vy", "vz", "wx", "wy", "wz"]
        header += [f"qd{j}" for j in range(m)] + [f"tau{j}" for j in range(m)]
        with open(out_path, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(header)
            for step, row in enumerate(targets, start=1):
                assert len(row) == m, f"{len(row)} targets for {m} movable joints"
                if m:
                    drive(client, robot, movable, row, forces, kp, kd, max_velocity)
                client.stepSimulation()
                pos, orn = client.getBasePositionAndOrientation(robot)
                lin, ang = client.getBaseVelocity(robot)
                states = client.getJointStates(robot, movable) if m else []
                out = [step, step * DT, *pos, *orn, *(s[0] for s in states), *lin, *ang]
                out += [s[1] for s in states] + [s[3] for s in states]
                writer.writerow([repr(v) if isinstance(v, float) else v for v in out])
    finally:
        client.disconnect()


def main(argv):
    if len(argv) != 3:
        sys.exit("usage: urdf_reference.py SCENARIOS.json OUT_DIR")
    with open(argv[1]) as f:
        scenarios = json.load(f)
    os.makedirs(argv[2], exist_ok=True)
    for scenario in scenarios:
        run(scenario, os.path.join(argv[2], scenario["name"] + ".csv"))


if __name__ == "__main__":
    main(sys.argv)
