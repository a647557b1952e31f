"""The paper's environment (snakebot-gym's Snake-v0) rebuilt in pybullet 3.2.7, for snakesim's env parity.

This follows snakebot/envs/SnakeEnv.py and snakebot/src/SnakeRobot.py of github.com/williamcorsel/snakebot-gym
step for step, with two changes that make it testable:

- the start pose is given by the scenario instead of drawn from the env's numpy generator;
- the goal marker is left out: the paper loads a static duck mesh (duck_vhacd.obj) one metre beyond the goal.
  It only matters if the snake touches it, and the episode ends within 1 m of the goal; snakesim leaves it
  out too.

As Stable-Baselines3 does before calling the paper's env (which does not clip), every action is clipped
to the action space in float32. Episodes end as gym's TimeLimit(max_episode_steps) and the env decide:
terminated when the base is within 1 m of the goal (reward 100), truncated after max_episode_steps.

Usage:
    python paper_env_reference.py SPEC.json OUT_DIR

SPEC.json:
    {"hypot": {"count": C, "seed": S},            # optional: math.hypot samples -> OUT_DIR/hypot.csv
     "envs": [{"name": NAME, "joints": N, "max_episode_steps": T, "goal_radius": 1,
               "episodes": [{"start": [x, y, z, yaw], "goal": [gx, gy], "actions": [[a0..aN-1], ...]}]}]}
Each episode k of env NAME is written to OUT_DIR/NAME-k.csv: columns step, reward, terminated, truncated,
obs0..obs{2+2N-1}; row 0 is the reset's observation (reward 0). Rows stop when the episode ends or the
actions run out. Floats are written with repr (float32 values widened to double exactly).

This file is independent of snakesim: it encodes the reference's behaviour from the paper's code.
"""

import csv
import json
import math
import os
import random
import sys

import numpy as np
import pybullet as p
from pybullet_utils import bullet_client

HALF_EXTENT = 0.25


def create_snake(client, joints, base_position, base_orientation, link_mass=1):
    """SnakeRobot.create_snake: base 0.06 kg, links `link_mass` (the paper's code: 1 kg), one shared
    GEOM_BOX, friction on every cube."""
    box = client.createCollisionShape(p.GEOM_BOX, halfExtents=[HALF_EXTENT] * 3)
    uid = client.createMultiBody(
        0.06,
        box,
        -1,
        base_position,
        base_orientation,
        linkMasses=[link_mass] * joints,
        linkCollisionShapeIndices=[box] * joints,
        linkVisualShapeIndices=[-1] * joints,
        linkPositions=[[0, HALF_EXTENT * 2.0 + 0.01, 0]] * joints,
        linkOrientations=[[0, 0, 0, 1]] * joints,
        linkInertialFramePositions=[[0, 0, 0]] * joints,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * joints,
        linkParentIndices=list(range(joints)),
        linkJointTypes=[p.JOINT_REVOLUTE] * joints,
        linkJointAxis=[[0, 0, 1]] * joints,
    )
    client.changeDynamics(uid, -1, lateralFriction=5, anisotropicFriction=[1, 0.01, 0.01])
    for i in range(client.getNumJoints(uid)):
        client.changeDynamics(uid, i, lateralFriction=5, anisotropicFriction=[1, 0.01, 0.01])
    return uid


def get_state(client, uid):
    """SnakeRobot.get_state: base x, y, then (angle, velocity) per joint via an object array, as float32."""
    position, _ = client.getBasePositionAndOrientation(uid)
    obs = np.array(position[:2])
    joint_data = np.array(client.getJointStates(uid, list(range(client.getNumJoints(uid)))), dtype=object)
    obs = np.append(obs, joint_data[:, 0:2])
    return obs.astype(np.float32)


def python_number(v):
    """The paper's goal is a tuple of Python ints; keep integral values as ints."""
    return int(v) if float(v).is_integer() else float(v)


def run_episode(env, episode, out_path):
    joints = env["joints"]
    goal = tuple(python_number(g) for g in episode["goal"])
    win_distance = python_number(env.get("goal_radius", 1))
    max_steps = env["max_episode_steps"]
    x, y, z, yaw = episode["start"]

    # SnakeEnv.reset
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    try:
        client.resetSimulation()
        plane = client.createCollisionShape(p.GEOM_PLANE)
        client.createMultiBody(0, plane)
        client.setRealTimeSimulation(0)
        client.setGravity(0, 0, -9.81)
        base_position = np.append(np.array([x, y]), z)
        base_orientation = client.getQuaternionFromEuler((0, 0, yaw))
        uid = create_snake(client, joints, base_position, base_orientation)
        client.stepSimulation()
        state = get_state(client, uid)

        header = ["step", "reward", "terminated", "truncated"] + [f"obs{i}" for i in range(len(state))]
        with open(out_path, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(header)
            writer.writerow([0, repr(0.0), 0, 0] + [repr(float(v)) for v in state])
            low, high = np.float32(-1), np.float32(1)
            for k, raw in enumerate(episode["actions"]):
                action = np.clip(np.array(raw, dtype=np.float32), low, high)
                # SnakeEnv.step: SnakeRobot.set_motors in position mode, one stepSimulation
                for joint in range(client.getNumJoints(uid)):
                    client.setJointMotorControl2(
                        uid, joint, p.POSITION_CONTROL, targetPosition=action[joint], force=10
                    )
                client.stepSimulation()
                state = get_state(client, uid)
                reward = -math.hypot(goal[0] - state[0], goal[1] - state[1])
                in_range = math.hypot(state[0] - goal[0], state[1] - goal[1]) < win_distance
                terminated = False
                if in_range:
                    terminated = True
                    reward = 100
                truncated = k + 1 >= max_steps  # gym's TimeLimit
                writer.writerow(
                    [k + 1, repr(float(reward)), int(terminated), int(truncated)]
                    + [repr(float(v)) for v in state]
                )
                if terminated or truncated:
                    break
    finally:
        client.disconnect()


def hypot_samples(count, seed, out_path):
    """math.hypot on float32 differences like the reward's and on doubles of every magnitude."""
    rng = random.Random(seed)
    with open(out_path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["x", "y", "hypot"])
        for i in range(count):
            kind = i % 4
            if kind == 0:
                # goal - float32 position, in float32 (numpy >= 2), widened
                gx, gy = rng.choice([0, -10, 3, 0.5]), rng.choice([0, -10, -1, 2.5])
                px, py = np.float32(rng.uniform(-12, 12)), np.float32(rng.uniform(-12, 12))
                x, y = float(gx - px), float(gy - py)
            elif kind == 1:
                x, y = rng.uniform(-30, 30), rng.uniform(-30, 30)
            elif kind == 2:
                x = rng.uniform(-1, 1) * 10.0 ** rng.randint(-320, 300)
                y = rng.uniform(-1, 1) * 10.0 ** rng.randint(-320, 300)
            else:
                x = rng.uniform(-1, 1) * 10.0 ** rng.randint(-12, 3)
                y = x * rng.choice([1.0, -1.0, 1e-9, 0.5, 3.0]) + rng.uniform(-1e-6, 1e-6)
            writer.writerow([repr(x), repr(y), repr(math.hypot(x, y))])


def main(argv):
    if len(argv) != 3:
        sys.exit("usage: paper_env_reference.py SPEC.json OUT_DIR")
    with open(argv[1]) as f:
        spec = json.load(f)
    os.makedirs(argv[2], exist_ok=True)
    if "hypot" in spec:
        hypot_samples(spec["hypot"]["count"], spec["hypot"]["seed"], os.path.join(argv[2], "hypot.csv"))
    for env in spec.get("envs", []):
        for k, episode in enumerate(env["episodes"]):
            run_episode(env, episode, os.path.join(argv[2], f"{env['name']}-{k}.csv"))


if __name__ == "__main__":
    main(sys.argv)
