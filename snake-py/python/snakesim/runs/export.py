"""Exporting a native policy as a Stable-Baselines3 model: ``snakesim export RUN --sb3 model.zip``.

The native network and SB3's ``MlpPolicy`` with snakesim's policy_kwargs are the same network with the
same tensor names (see snake-rl's ``nn::network``), so the weights move over one to one. A policy that
normalises observations also gets its statistics, as a ``VecNormalize`` pickle beside the zip
(``<name>_vecnormalize.pkl``): load it with ``VecNormalize.load(path, venv)`` and normalise observations
before ``predict``. The env keywords go into the zip's ``data`` (``snakesim_env_kwargs``, plain JSON), so
``snakesim evaluate NAME.zip`` runs the env the native model names.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from snakesim import extras
from snakesim.agents.sb3_zip import EXPORTED_ASSIST_KEY, EXPORTED_ENV_KEY, RECORDED_FILES_KEY
from snakesim.files import write_atomically
from snakesim.runs.rundir import EXPORTED_STATISTICS_SUFFIX


def vecnormalize_path(zip_path: str | os.PathLike) -> Path:
    """Where the observation statistics of an exported model go."""
    path = Path(zip_path)
    return path.with_name(path.stem + EXPORTED_STATISTICS_SUFFIX)


def to_sb3(agent: Any, path: str | os.PathLike) -> list[Path]:
    """Writes the native ``agent`` (see :func:`snakesim.agents.load_agent`) as an SB3 PPO zip; returns
    the files written; ValueError for an agent that says it does not export so (``exports_sb3``)."""
    extras.require("sb3", "snakesim export --sb3")
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from snakesim.envs.sb3 import SnakeVecEnv
    from snakesim.runs.policies import policy_kwargs

    if not agent.exports_sb3:
        raise ValueError(f"{agent.path} is not a native model (it is already an SB3 model)")
    env = SnakeVecEnv(1, **agent.env_kwargs)
    hyper: dict[str, Any] = {}
    if agent.config is not None:
        from snakesim.runs import config as runconfig

        ppo = agent.config["ppo"]
        hyper = {
            key: runconfig.schedule(ppo[key]) if key in ("learning_rate", "clip_range") else ppo[key]
            for key in (
                "learning_rate",
                "n_steps",
                "batch_size",
                "n_epochs",
                "gamma",
                "gae_lambda",
                "clip_range",
            )
        }
    kwargs = policy_kwargs(agent.policy.net_arch)
    model = PPO("MlpPolicy", env, policy_kwargs=kwargs, device="cpu", seed=0, **hyper)
    state = model.policy.state_dict()
    for name, array in agent.policy.tensors().items():
        aliases = [name]
        if name.startswith("features_extractor."):
            rest = name[len("features_extractor.") :]
            aliases += [f"pi_features_extractor.{rest}", f"vf_features_extractor.{rest}"]
        for alias in aliases:
            if alias not in state:
                raise ValueError(f"{agent.path}: tensor {alias} has no place in SB3's {agent.arch} policy")
            state[alias] = torch.from_numpy(np.array(array, dtype=np.float32))
    model.policy.load_state_dict(state)
    model.num_timesteps = int(agent.num_timesteps or 0)
    # The env it was trained in, as plain JSON in the zip's data (snakesim reads it back; PPO.load
    # sets it as an attribute and ignores it), so the export evaluates on the native model's env.
    setattr(model, EXPORTED_ENV_KEY, dict(agent.env_kwargs))
    # The texts of its robot and world files, as the native model records them (env_files).
    records = agent.policy.env_files_json()
    if records is not None:
        setattr(model, RECORDED_FILES_KEY, json.loads(records))
    if agent.steer_assist is not None:
        # Plain JSON, as the env keywords: PPO.load users apply it with snakesim.wrappers.SteerAssist.
        setattr(model, EXPORTED_ASSIST_KEY, json.loads(agent.steer_assist.to_json()))
    out = Path(path)
    # SB3 appends ".zip" only to a name without a suffix; the temporary file ends in .zip.
    write_atomically(out, model.save)
    written = [out]
    stats = agent.policy.obs_rms()
    if stats is not None:
        mean, var, count = stats
        normalizer = VecNormalize(env, training=False, norm_obs=True, norm_reward=False)
        normalizer.obs_rms.mean = np.array(mean, dtype=np.float64)
        normalizer.obs_rms.var = np.array(var, dtype=np.float64)
        normalizer.obs_rms.count = float(count)
        target = vecnormalize_path(out)
        write_atomically(target, normalizer.save)
        written.append(target)
    return written
