# The simulated robot that docs/deploy.md's control loops run against in
# snake-py/tests/test_doc_examples.py (`<!-- test prelude: ... -->`, run before the block in the same
# interpreter; the model's ONNX file is the script's first argument). The loops are written for
# hardware: `robot` reads joints and position and takes joint targets in radians. By default it is the
# model's env driven joint by joint at 240 Hz (one physics step per `set_joint_targets`), so a
# gait-mode loop's wave runs on the robot's side as on hardware; the episode must end at the goal.
# With `--compare-targets` (the residual-mode loop, whose tiny test model need not reach the goal) it is
# the model's own env, in its own action mode and control rate: once the loop has set a control
# period's targets, the env takes the ONNX file's action for the env's own observation, and the loop's
# targets must equal those the env set (its physics trace) to 1e-12 rad, over a whole episode.
import atexit
import json
import os
import sys
import time

import numpy as np
import onnxruntime
import snakesim

time.sleep = lambda seconds: None  # the simulation keeps its own time


class Robot:
    """What both robots share: the observation's parts, the joints, the position."""

    def __init__(self, onnx_path: str):
        self.session = onnxruntime.InferenceSession(onnx_path, providers=["CPUExecutionProvider"])
        self.meta = {k: json.loads(v) for k, v in self.session.get_modelmeta().custom_metadata_map.items()}
        self.done = False

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


class SimRobot(Robot):
    #: Joint targets per unit of action of the joint-driven env: a wave reaches amplitude + steering.
    SCALE = 1.5

    def __init__(self, onnx_path: str, seed: int = 0):
        super().__init__(onnx_path)
        kwargs = dict(self.meta["snakesim.env_kwargs"])
        steps = self.meta["snakesim.physics_steps_per_env_step"]
        limit = snakesim.envs.env.make_env(**kwargs).config["max_episode_steps"] * steps
        kwargs.update(
            action={"mode": "joints"},
            action_scale=self.SCALE,
            physics_steps_per_env_step=1,
            max_episode_steps=limit,
        )
        self.env = snakesim.envs.env.make_env(**kwargs)
        self.obs, _ = self.env.reset(seed=seed)
        self.success = False
        self.steps = 0

    def set_joint_targets(self, targets) -> None:
        self.obs, _, terminated, truncated, info = self.env.step(np.asarray(targets) / self.SCALE)
        self.steps += 1
        if terminated or truncated:
            self.done = True
            self.success = bool(info.get("success"))

    def check(self) -> bool:
        print(f"simulated robot: {self.steps} physics steps, success {self.success}")
        return self.success


class EnvRobot(Robot):
    """The model's own env; the loop's joint targets are compared with the env's own."""

    #: rad: an ulp of a sine passes, a float32 step anywhere (about 1e-9 here) does not.
    TOLERANCE = 1e-12

    def __init__(self, onnx_path: str, seed: int = 0):
        super().__init__(onnx_path)
        self.env = snakesim.envs.env.make_env(**self.meta["snakesim.env_kwargs"])
        self.env.set_physics_trace(True)
        self.per_action = self.meta["snakesim.physics_steps_per_env_step"]
        self.obs, _ = self.env.reset(seed=seed)
        self.pending: list[np.ndarray] = []
        self.actions = 0
        self.largest = 0.0
        self.ended = False

    def set_joint_targets(self, targets) -> None:
        self.pending.append(np.asarray(targets, dtype=np.float64))
        if len(self.pending) < self.per_action:
            return
        action = self.session.run(["action"], {"observation": self.obs[None, :]})[0][0]
        self.obs, _, terminated, truncated, _ = self.env.step(action)
        own = self.env.physics_trace()["targets"]
        self.largest = max(self.largest, float(np.abs(np.array(self.pending) - own).max()))
        self.pending.clear()
        self.actions += 1
        self.ended = self.done = bool(terminated or truncated)

    def check(self) -> bool:
        print(
            f"simulated robot: {self.actions} actions of the model's own env, the loop's joint targets "
            f"within {self.largest:.1e} rad of the env's (episode ended: {self.ended})"
        )
        return self.ended and self.actions > 0 and self.largest <= self.TOLERANCE


robot = (EnvRobot if "--compare-targets" in sys.argv[2:] else SimRobot)(sys.argv[1])


@atexit.register
def _checked():
    if not robot.check():
        sys.stdout.flush()
        os._exit(1)
