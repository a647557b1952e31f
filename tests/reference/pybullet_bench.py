"""pybullet 3.2.7's physics steps per second on the paper's snake driven by snake.py's gait.

Usage: python pybullet_bench.py JOINTS_CSV STEPS REPEATS
Prints one JSON object: {"<joints>": [steps/s of each repeat], ...}. Each repeat builds a fresh
world and times only the control-and-step loop, as `snake-cli bench` does for snakesim.
"""

import json
import math
import os
import sys
import time

import pybullet as p
from pybullet_utils import bullet_client

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paper_env_reference import create_snake  # noqa: E402

HALF = 0.25
DT = 1.0 / 240.0


def build(client, joints):
    """The paper's snake (every cube 0.06 kg) resting on the plane."""
    client.createMultiBody(0, client.createCollisionShape(p.GEOM_PLANE))
    client.setGravity(0, 0, -9.81)
    return create_snake(client, joints, [0, 0, HALF], [0, 0, 0, 1], link_mass=0.06)


def timed_gait(client, uid, joints, steps):
    """Steps/s of snake.py's gait on the snake ``uid``: the control-and-step loop alone, then the
    client is disconnected."""
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


def one_run(joints, steps):
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    return timed_gait(client, build(client, joints), joints, steps)


def main():
    joints = [int(j) for j in sys.argv[1].split(",")]
    steps, repeats = int(sys.argv[2]), int(sys.argv[3])
    print(json.dumps({str(n): [one_run(n, steps) for _ in range(repeats)] for n in joints}))


if __name__ == "__main__":
    main()
