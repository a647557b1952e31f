"""The paper's env (snakebot-gym's Snake-v0) in pybullet 3.2.7 as a Gymnasium env, for benchmarks and
for training comparisons against the reference.

It builds the world as paper_env_reference.py does (the same functions), draws the start as the paper
does (x, y ~ U(-0.5, 0.5), z 0.5, yaw ~ U(-0.2, 0.2) from the env's generator) and truncates after
max_episode_steps. Unlike the paper, a reset disconnects the previous pybullet client instead of
leaking it (the paper opens a new client at every reset).
"""

import math
import os
import sys

import gymnasium
import numpy as np
import pybullet as p
from gymnasium import spaces
from pybullet_utils import bullet_client

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paper_env_reference import create_snake, get_state  # noqa: E402


class PaperSnakeEnv(gymnasium.Env):
    """snakebot-gym's SnakeEnv (position mode) with the Gymnasium API."""

    def __init__(self, joints=5, goal=(0, -10), max_episode_steps=5000):
        self.joints = joints
        self.goal = goal
        self.max_episode_steps = max_episode_steps
        self.action_space = spaces.Box(-1, 1, (joints,), dtype=np.float32)
        self.observation_space = spaces.Box(-np.inf, np.inf, (2 + 2 * joints,), dtype=np.float32)
        self._client = None
        self._uid = None
        self._steps = 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        if self._client is not None:
            self._client.disconnect()
        self._client = bullet_client.BulletClient(connection_mode=p.DIRECT)
        client = self._client
        client.resetSimulation()
        client.createMultiBody(0, client.createCollisionShape(p.GEOM_PLANE))
        client.setRealTimeSimulation(0)
        client.setGravity(0, 0, -9.81)
        position = np.append(self.np_random.uniform(low=-0.5, high=0.5, size=2), 0.5)
        orientation = client.getQuaternionFromEuler((0, 0, self.np_random.uniform(low=-0.2, high=0.2)))
        self._uid = create_snake(client, self.joints, position, orientation)
        client.stepSimulation()
        self._steps = 0
        return get_state(client, self._uid), {}

    def step(self, action):
        client = self._client
        for joint in range(self.joints):
            client.setJointMotorControl2(
                self._uid, joint, p.POSITION_CONTROL, targetPosition=action[joint], force=10
            )
        client.stepSimulation()
        state = get_state(client, self._uid)
        distance = math.hypot(self.goal[0] - state[0], self.goal[1] - state[1])
        terminated = distance < 1
        reward = 100 if terminated else -distance
        self._steps += 1
        truncated = self._steps >= self.max_episode_steps
        return state, float(reward), terminated, truncated, {}

    def close(self):
        if self._client is not None:
            self._client.disconnect()
            self._client = None
