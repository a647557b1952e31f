"""pybullet 3.2.7's physics steps per second on the paper's snake driven by snake.py's gait.

Usage: python pybullet_bench.py JOINTS_CSV STEPS REPEATS
Prints one JSON object: {"<joints>": [steps/s of each repeat], ...}. Each repeat builds a fresh
world and times only the control-and-step loop, as `snake-cli bench` does for snakesim.
"""

import json
import math
import sys
import time

import pybullet as p
from pybullet_utils import bullet_client

HALF = 0.25
DT = 1.0 / 240.0


def build(client, joints):
    client.createMultiBody(0, client.createCollisionShape(p.GEOM_PLANE))
    client.setGravity(0, 0, -9.81)
    box = client.createCollisionShape(p.GEOM_BOX, halfExtents=[HALF] * 3)
    uid = client.createMultiBody(
        0.06,
        box,
        -1,
        [0, 0, HALF],
        [0, 0, 0, 1],
        linkMasses=[0.06] * joints,
        linkCollisionShapeIndices=[box] * joints,
        linkVisualShapeIndices=[-1] * joints,
        linkPositions=[[0, HALF * 2.0 + 0.01, 0]] * joints,
        linkOrientations=[[0, 0, 0, 1]] * joints,
        linkInertialFramePositions=[[0, 0, 0]] * joints,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * joints,
        linkParentIndices=list(range(joints)),
        linkJointTypes=[p.JOINT_REVOLUTE] * joints,
        linkJointAxis=[[0, 0, 1]] * joints,
    )
    for link in range(-1, joints):
        client.changeDynamics(uid, link, lateralFriction=5, anisotropicFriction=[1, 0.01, 0.01])
    return uid


def one_run(joints, steps):
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    uid = build(client, joints)
    indices = list(range(joints))
    forces = [10.0] * joints
    front = 0.0
    start = time.perf_counter()
    for _ in range(steps):
        scale = front / 2.0 if front < 2.0 else 1.0
        targets = []
        for j in indices:
            phase = (front - (j + 1) * 0.5) / 4.0
            phase -= math.floor(phase)
            targets.append(math.sin(phase * math.pi * 2.0) * scale * 0.4)
        client.setJointMotorControlArray(
            uid, indices, p.POSITION_CONTROL, targetPositions=targets, forces=forces
        )
        front += DT / 1.5 * 4.0
        client.stepSimulation()
    elapsed = time.perf_counter() - start
    client.disconnect()
    return steps / elapsed


def main():
    joints = [int(j) for j in sys.argv[1].split(",")]
    steps, repeats = int(sys.argv[2]), int(sys.argv[3])
    print(json.dumps({str(n): [one_run(n, steps) for _ in range(repeats)] for n in joints}))


if __name__ == "__main__":
    main()
