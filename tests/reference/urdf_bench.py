"""pybullet 3.2.7's physics steps per second on a URDF robot driven by given joint targets.

Usage: python urdf_bench.py SCENARIO.json REPEATS
SCENARIO.json is one scenario of urdf_reference.py. Prints one JSON list: steps/s of each repeat. Each
repeat loads a fresh world and times only the control-and-step loop (setJointMotorControlArray with the
URDF efforts, stepSimulation), as `snake-cli bench --robot` does for snakesim.
"""

import json
import os
import sys
import time

import pybullet as p
from pybullet_utils import bullet_client

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from urdf_reference import load  # noqa: E402


def one_run(scenario):
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    robot, movable, forces, kp, kd, targets = load(client, scenario)
    m = len(movable)
    kps, kds = [kp] * m, [kd] * m
    start = time.perf_counter()
    for row in targets:
        client.setJointMotorControlArray(
            robot,
            movable,
            p.POSITION_CONTROL,
            targetPositions=row,
            forces=forces,
            positionGains=kps,
            velocityGains=kds,
        )
        client.stepSimulation()
    elapsed = time.perf_counter() - start
    client.disconnect()
    return len(targets) / elapsed


def main():
    with open(sys.argv[1]) as f:
        scenario = json.load(f)
    repeats = int(sys.argv[2])
    print(json.dumps([one_run(scenario) for _ in range(repeats)]))


if __name__ == "__main__":
    main()
