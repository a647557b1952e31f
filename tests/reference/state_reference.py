"""The pybullet 3.2.7 reference for the state primitives media and calibration build on.

The paper's cube snake (10 joints, preset "paper") on the plane, driven by snake.py's wave with force 10;
every step it also gets an external force on link 3 at a point off its centre (applyExternalForce,
WORLD_FRAME) and a torque on the base (applyExternalTorque, WORLD_FRAME), and at step RESET_STEP its base
and joints are set (resetBasePositionAndOrientation, resetBaseVelocity, resetJointState). After every
step one CSV row: the columns of pybullet_reference.py, then each link's world-frame velocity from
getLinkState(computeLinkVelocity=1) (vx, vy, vz, wx, wy, wz per link).

Usage:
    python state_reference.py SPEC.json OUT_DIR      (SPEC: {"steps": N}; writes OUT_DIR/state.csv)

This file is independent of snakesim: it is what a pybullet user writes.
"""

import csv
import json
import math
import os
import sys

import pybullet as p
from pybullet_utils import bullet_client

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paper_env_reference import create_snake  # noqa: E402
from pybullet_reference import SnakeWave  # noqa: E402

DT = 1.0 / 240.0
JOINTS = 10
RESET_STEP = 200
# The state set at RESET_STEP: a base pose and velocity, and every joint's angle and velocity.
RESET_POSITION = [0.3, -0.2, 0.4]
# A unit quaternion (x, y, z, w) written so that both sides compute the same bits.
RESET_XYZ = [0.02, -0.015, 0.34]
RESET_QUATERNION = [*RESET_XYZ, math.sqrt(1.0 - sum(v * v for v in RESET_XYZ))]
RESET_LINEAR = [0.2, -0.1, 0.05]
RESET_ANGULAR = [0.0, 0.1, 0.3]


def reset_joint(j):
    return 0.3 * math.sin(0.7 * j), 0.5 * math.cos(1.3 * j)


def push(k):
    """The external force on link 3 (N), its point's offset from the link's centre (m), the base torque."""
    t = k * DT
    return (
        [3.0 * math.sin(2.0 * t), 1.5, 2.0 * math.cos(3.0 * t)],
        [0.1, -0.2, 0.05],
        [0.0, 0.0, 0.4 * math.cos(t)],
    )


def main(argv):
    with open(argv[1]) as f:
        steps = json.load(f)["steps"]
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    client.createMultiBody(0, client.createCollisionShape(p.GEOM_PLANE))
    client.setGravity(0, 0, -9.81)
    uid = create_snake(client, JOINTS, [0, 0, 0.25], [0, 0, 0, 1], link_mass=0.06)
    wave = SnakeWave()
    os.makedirs(argv[2], exist_ok=True)
    with open(os.path.join(argv[2], "state.csv"), "w", newline="") as f:
        writer = csv.writer(f)
        header = ["step", "t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw"]
        header += [f"q{j}" for j in range(JOINTS)] + ["vx", "vy", "vz", "wx", "wy", "wz"]
        header += [f"qd{j}" for j in range(JOINTS)] + [f"tau{j}" for j in range(JOINTS)]
        header += [f"link{j}_{c}" for j in range(JOINTS) for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
        writer.writerow(header)
        for step in range(1, steps + 1):
            k = step - 1
            if k == RESET_STEP:
                client.resetBasePositionAndOrientation(uid, RESET_POSITION, RESET_QUATERNION)
                client.resetBaseVelocity(uid, RESET_LINEAR, RESET_ANGULAR)
                for j in range(JOINTS):
                    angle, velocity = reset_joint(j)
                    client.resetJointState(uid, j, angle, velocity)
            for j, target in enumerate(wave.targets(JOINTS)):
                client.setJointMotorControl2(uid, j, p.POSITION_CONTROL, targetPosition=target, force=10.0)
            force, offset, torque = push(k)
            centre = client.getLinkState(uid, 3)[0]
            point = [c + o for c, o in zip(centre, offset)]
            client.applyExternalForce(uid, 3, force, point, p.WORLD_FRAME)
            client.applyExternalTorque(uid, -1, torque, p.WORLD_FRAME)
            client.stepSimulation()
            pos, orn = client.getBasePositionAndOrientation(uid)
            lin, ang = client.getBaseVelocity(uid)
            states = client.getJointStates(uid, list(range(JOINTS)))
            row = [step, step * DT, *pos, *orn, *(s[0] for s in states), *lin, *ang]
            row += [s[1] for s in states] + [s[3] for s in states]
            for j in range(JOINTS):
                link = client.getLinkState(uid, j, computeLinkVelocity=1)
                row += [*link[6], *link[7]]
            writer.writerow([repr(v) if isinstance(v, float) else v for v in row])
    client.disconnect()


if __name__ == "__main__":
    main(sys.argv)
