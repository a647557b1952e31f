"""Native models (a ``.safetensors`` file, or a native run's): Rust reads and checks them, and the
policy (a ``_core.NativePolicy``) normalises its observations itself."""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from snakesim.agents.protocol import Agent, AgentError
from snakesim.agents.recorded import agreed_env, bind_assist, check_env, note

if TYPE_CHECKING:  # pragma: no cover - names for annotations only
    from snakesim.runs.onnx import Actor, Normalization


@dataclasses.dataclass
class NativeAgent(Agent):
    """A native model; ``policy`` is a ``_core.NativePolicy``."""

    kind: ClassVar[str] = "native"
    trainer: ClassVar[str] = "native trainer"
    exports_sb3: ClassVar[bool] = True

    @classmethod
    def read(
        cls,
        located: Any,
        *,
        joints: int | None,
        preset: str | None,
        overrides: Mapping[str, Any] | None,
        device: str = "cpu",
    ) -> NativeAgent:
        """The model of ``located`` (a :class:`snakesim.agents.locate.Located`); ``device`` is
        torch's, which a native model does not use."""
        from snakesim import _core

        model: Path = located.model
        try:
            policy = _core.NativePolicy(os.fspath(model))
        except ValueError as error:
            raise AgentError(str(error)) from None
        note(policy.notes, overrides)
        recorded = {"joints": policy.joints, "preset": policy.preset, **json.loads(policy.env_json())}
        env_kwargs = agreed_env(model, recorded, joints, preset, overrides)
        check_env(model, env_kwargs, policy.obs_dim, policy.act_dim)
        return cls(
            policy=policy,
            path=os.fspath(model),
            env_kwargs=env_kwargs,
            arch=policy.arch,
            sb3_version="native",
            num_timesteps=policy.timesteps,
            config=located.config,
            files=located.files,
            steer_assist=bind_assist(model, policy.steer_assist_json(), env_kwargs),
        )

    def own_actions(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        # The native policy normalises observations itself (with its saved statistics).
        return self.policy.act(np.ascontiguousarray(obs, dtype=np.float32), deterministic)

    def normalization(self) -> Normalization | None:
        """The saved statistics, with snake-rl's epsilon and clip (``normalize.rs``)."""
        from snakesim.runs.onnx import NATIVE_CLIP, NATIVE_EPSILON, Normalization

        stats = self.policy.obs_rms()
        if stats is None:
            return None
        mean, var, _ = stats
        return Normalization(
            np.asarray(mean, np.float64), np.asarray(var, np.float64), NATIVE_EPSILON, NATIVE_CLIP
        )

    def actor(self) -> Actor:
        from snakesim.runs.onnx import native_actor

        return native_actor(self.policy, self.normalization())
