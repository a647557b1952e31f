# The simulated robot that docs/deploy.md's control loops run against in
# snake-py/tests/test_doc_examples.py (`<!-- test prelude: ... -->`, run before the block in the same
# interpreter; the model's ONNX file is the script's first argument). The loops are written for
# hardware: `robot` reads joints and position and takes joint targets in radians. Here it is the
# model's own env driven joint by joint at 240 Hz (one physics step per `set_joint_targets`), so a
# gait-mode loop's wave runs on the robot's side as on hardware. The episode must end at the goal.
import atexit
import json
import os
import sys
import time

import numpy as np
import onnxruntime
import snakesim

time.sleep = lambda seconds: None  # the simulation keeps its own time


class SimRobot:
    #: Joint targets per unit of action of the joint-driven env: a wave reaches amplitude + steering.
    SCALE = 1.5

    def __init__(self, onnx_path: str, seed: int = 0):
        session = onnxruntime.InferenceSession(onnx_path, providers=["CPUExecutionProvider"])
        meta = {k: json.loads(v) for k, v in session.get_modelmeta().custom_metadata_map.items()}
        kwargs = dict(meta["snakesim.env_kwargs"])
        steps = meta["snakesim.physics_steps_per_env_step"]
        limit = snakesim.envs.env.make_env(**kwargs).config["max_episode_steps"] * steps
        kwargs.update(
            action={"mode": "joints"},
            action_scale=self.SCALE,
            physics_steps_per_env_step=1,
            max_episode_steps=limit,
        )
        self.env = snakesim.envs.env.make_env(**kwargs)
        self.obs, _ = self.env.reset(seed=seed)
        self.done = False
        self.success = False
        self.steps = 0

    def running(self) -> bool:
        return not self.done

    def stop(self) -> None:
        self.done = True

    def read_parts(self) -> dict[str, np.ndarray]:
        parts, start = {}, 0
        for name, size in self.env.observation_structure.items():
            parts[name] = self.obs[start : start + size]
            start += size
        return parts

    def read_joints(self) -> tuple[np.ndarray, np.ndarray]:
        states = self.read_parts()["joint_states"].reshape(-1, 2)
        return states[:, 0], states[:, 1]

    def head_xy(self) -> np.ndarray:
        return self.read_parts()["base_position"]

    def set_joint_targets(self, targets) -> None:
        self.obs, _, terminated, truncated, info = self.env.step(np.asarray(targets) / self.SCALE)
        self.steps += 1
        if terminated or truncated:
            self.done = True
            self.success = bool(info.get("success"))


robot = SimRobot(sys.argv[1])


@atexit.register
def _reached_the_goal():
    print(f"simulated robot: {robot.steps} physics steps, success {robot.success}")
    if not robot.success:
        sys.stdout.flush()
        os._exit(1)
