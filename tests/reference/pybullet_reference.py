"""The pybullet 3.2.7 reference for snakesim's parity tests.

Builds the paper's snake exactly as the reference code does (plane first, then gravity, the snake as one
createMultiBody with a shared GEOM_BOX shape, then changeDynamics on the base and every link) and runs
a scenario, writing one CSV row per 1/240 s step with the state after that step.

Usage:
    python pybullet_reference.py SCENARIOS.json OUT_DIR

SCENARIOS.json is a list of scenarios; each is written to OUT_DIR/<name>.csv. A scenario:
    name       file stem
    joints     N (N + 1 cubes)
    preset     "paper" (all cubes 0.06 kg) or "snakebot-gym" (base 0.06 kg, links 1.0 kg)
    start      [x, y, z, yaw]
    steps      number of physics steps
    control    {"mode": "gait" | "zero" | "position" | "velocity" | "torque", ...}: see targets()
    dynamics   optional changeDynamics keywords applied to every cube after the preset's friction
Columns: step, t, base_x, base_y, base_z, base_qx, base_qy, base_qz, base_qw, q0..q{N-1}, then
vx, vy, vz, wx, wy, wz and qd0..qd{N-1}, tau0..tau{N-1} (motor torques).

This file is independent of snakesim: it encodes the reference's behaviour from the paper's code and
pybullet's snake.py, not from our implementation.
"""

import csv
import json
import math
import os
import sys

import pybullet as p
from pybullet_utils import bullet_client

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paper_env_reference import HALF_EXTENT, create_snake  # noqa: E402

DT = 1.0 / 240.0
MASSES = {"paper": (0.06, 0.06), "snakebot-gym": (0.06, 1.0)}


def build(client, joints, preset, start):
    """The plane, gravity, then the snake as the paper's code builds it."""
    base_mass, link_mass = MASSES[preset]
    assert base_mass == 0.06, "create_snake builds the paper's 0.06 kg base"
    plane = client.createCollisionShape(p.GEOM_PLANE)
    client.createMultiBody(0, plane)
    client.setGravity(0, 0, -9.81)
    x, y, z, yaw = start
    orientation = client.getQuaternionFromEuler((0, 0, yaw))
    return create_snake(client, joints, [x, y, z], orientation, link_mass=link_mass)


class SnakeWave:
    """pybullet's examples/snake.py wave, step by step."""

    def __init__(self, steering=0.0):
        self.front = 0.0
        self.steering = steering

    def targets(self, joints):
        wave_length, period, amplitude, segment = 4, 1.5, 0.4, HALF_EXTENT * 2.0
        scale = 1.0
        if self.front < segment * 4.0:
            scale = self.front / (segment * 4.0)
        out = []
        for joint in range(joints):
            phase = (self.front - (joint + 1) * segment) / wave_length
            phase -= math.floor(phase)
            phase *= math.pi * 2.0
            target = math.sin(phase) * scale * amplitude
            if self.steering > 0 and target < 0:
                target *= 1.0 / (1.0 + self.steering)
            if self.steering < 0 and target > 0:
                target *= 1.0 / (1.0 - self.steering)
            out.append(target + self.steering)
        self.front += DT / period * wave_length
        return out


def signal(step, joint, amplitude):
    """A smooth, joint-dependent test signal: amplitude * sin(2 pi * 0.8 * t + 0.7 * joint)."""
    return amplitude * math.sin(2.0 * math.pi * 0.8 * (step * DT) + 0.7 * joint)


def run(scenario, out_path):
    joints = scenario["joints"]
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    try:
        uid = build(client, joints, scenario["preset"], scenario["start"])
        for link in range(-1, joints):
            if scenario.get("dynamics"):
                client.changeDynamics(uid, link, **scenario["dynamics"])
        control = scenario["control"]
        mode = control["mode"]
        wave = SnakeWave(control.get("steering", 0.0))
        force = control.get("force", 10.0)
        if mode == "torque":
            # The default motors stay active under TORQUE_CONTROL until switched off.
            for j in range(joints):
                client.setJointMotorControl2(uid, j, p.VELOCITY_CONTROL, force=0)
        header = ["step", "t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw"]
        header += [f"q{j}" for j in range(joints)]
        header += ["vx", "vy", "vz", "wx", "wy", "wz"]
        header += [f"qd{j}" for j in range(joints)] + [f"tau{j}" for j in range(joints)]
        with open(out_path, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(header)
            for step in range(1, scenario["steps"] + 1):
                k = step - 1  # the control of a step uses the state before it
                if mode == "gait":
                    for j, target in enumerate(wave.targets(joints)):
                        client.setJointMotorControl2(
                            uid, j, p.POSITION_CONTROL, targetPosition=target, force=force
                        )
                elif mode == "zero":
                    for j in range(joints):
                        client.setJointMotorControl2(
                            uid, j, p.POSITION_CONTROL, targetPosition=0.0, force=force
                        )
                elif mode == "position":
                    for j in range(joints):
                        client.setJointMotorControl2(
                            uid,
                            j,
                            p.POSITION_CONTROL,
                            targetPosition=signal(k, j, 0.5),
                            targetVelocity=control.get("target_velocity", 0.0),
                            force=force,
                            positionGain=control["kp"],
                            velocityGain=control["kd"],
                            maxVelocity=control.get("max_velocity", -1),
                        )
                elif mode == "velocity":
                    for j in range(joints):
                        client.setJointMotorControl2(
                            uid, j, p.VELOCITY_CONTROL, targetVelocity=signal(k, j, 3.0), force=force
                        )
                elif mode == "torque":
                    for j in range(joints):
                        client.setJointMotorControl2(uid, j, p.TORQUE_CONTROL, force=signal(k, j, force))
                else:
                    raise ValueError(f"unknown control mode {mode!r}")
                client.stepSimulation()
                pos, orn = client.getBasePositionAndOrientation(uid)
                lin, ang = client.getBaseVelocity(uid)
                states = client.getJointStates(uid, list(range(joints)))
                row = [step, step * DT, *pos, *orn, *(s[0] for s in states), *lin, *ang]
                row += [s[1] for s in states] + [s[3] for s in states]
                writer.writerow([repr(v) if isinstance(v, float) else v for v in row])
    finally:
        client.disconnect()


def main(argv):
    if len(argv) != 3:
        sys.exit("usage: pybullet_reference.py SCENARIOS.json OUT_DIR")
    with open(argv[1]) as f:
        scenarios = json.load(f)
    os.makedirs(argv[2], exist_ok=True)
    for scenario in scenarios:
        run(scenario, os.path.join(argv[2], scenario["name"] + ".csv"))


if __name__ == "__main__":
    main(sys.argv)
