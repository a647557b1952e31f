"""The paper's networks in SB3 2.x, and loading SB3 1.x agents (as the paper published them)."""

import io
import json
import zipfile

import numpy as np
import pytest
import torch
from snakesim import SnakeVecEnv
from snakesim.agents.loading import inspect_model, load_agent
from snakesim.runs.policies import (
    convert_legacy_state_dict,
    parameter_count,
    parse_legacy_net_arch,
    policy_kwargs,
)
from stable_baselines3 import PPO


def linear(n_in, n_out):
    return n_in * n_out + n_out


def paper_count(joints, arch):
    """Parameters of SB3 1.x's ActorCriticPolicy with the paper's net_arch, counted by hand.

    small: net_arch [dict(pi=[64, 64], vf=[64, 64])] (1.x's default); large: [128, 128, dict(pi=[64, 64],
    vf=[64, 64])]. Plus action_net (64 -> N), value_net (64 -> 1) and log_std (N).
    """
    obs, act = 2 + 2 * joints, joints
    if arch == "small":
        trunk, head_in = 0, obs
    else:
        trunk, head_in = linear(obs, 128) + linear(128, 128), 128
    head = linear(head_in, 64) + linear(64, 64)
    return trunk + 2 * head + linear(64, act) + linear(64, 1) + act


@pytest.mark.parametrize(
    ("joints", "arch", "expected"),
    [(5, "small", 10379), (10, "small", 11989), (5, "large", 43403), (10, "large", 45013)],
)
def test_parameter_counts_match_the_papers_networks(joints, arch, expected):
    assert paper_count(joints, arch) == expected
    model = PPO("MlpPolicy", SnakeVecEnv(2, joints=joints), policy_kwargs=policy_kwargs(arch), device="cpu")
    assert parameter_count(model.policy) == expected
    # The shared layers are one module, stepped once by the optimizer.
    assert (
        sum(p.numel() for group in model.policy.optimizer.param_groups for p in group["params"]) == expected
    )


def test_parse_legacy_net_arch():
    assert parse_legacy_net_arch(None) == ("small", [])
    assert parse_legacy_net_arch([{"pi": [64, 64], "vf": [64, 64]}]) == ("small", [])
    assert parse_legacy_net_arch([128, 128, {"pi": [64, 64], "vf": [64, 64]}]) == ("large", [128, 128])
    with pytest.raises(ValueError, match="unsupported"):
        parse_legacy_net_arch([64, 64])
    with pytest.raises(ValueError, match="unsupported"):
        parse_legacy_net_arch([128, {"pi": [32], "vf": [32]}])


def legacy_state(joints, shared, seed=0):
    """A state dict laid out as SB3 1.x's ActorCriticPolicy saved it (the paper's published zips)."""
    g = torch.Generator().manual_seed(seed)
    obs = 2 + 2 * joints
    shapes = {"log_std": (joints,)}
    width = obs
    if shared:
        shapes |= {
            "mlp_extractor.shared_net.0.weight": (128, obs),
            "mlp_extractor.shared_net.0.bias": (128,),
            "mlp_extractor.shared_net.2.weight": (128, 128),
            "mlp_extractor.shared_net.2.bias": (128,),
        }
        width = 128
    for net in ("policy_net", "value_net"):
        shapes |= {
            f"mlp_extractor.{net}.0.weight": (64, width),
            f"mlp_extractor.{net}.0.bias": (64,),
            f"mlp_extractor.{net}.2.weight": (64, 64),
            f"mlp_extractor.{net}.2.bias": (64,),
        }
    shapes |= {
        "action_net.weight": (joints, 64),
        "action_net.bias": (joints,),
        "value_net.weight": (1, 64),
        "value_net.bias": (1,),
    }
    return {key: torch.randn(shape, generator=g) * 0.3 for key, shape in shapes.items()}


def legacy_forward(state, obs, shared):
    """1.x's deterministic action and value, written out."""
    x = torch.as_tensor(obs)
    if shared:
        for i in (0, 2):
            x = torch.tanh(
                x @ state[f"mlp_extractor.shared_net.{i}.weight"].T
                + state[f"mlp_extractor.shared_net.{i}.bias"]
            )
    out = {}
    for net in ("policy_net", "value_net"):
        h = x
        for i in (0, 2):
            h = torch.tanh(
                h @ state[f"mlp_extractor.{net}.{i}.weight"].T + state[f"mlp_extractor.{net}.{i}.bias"]
            )
        out[net] = h
    action = out["policy_net"] @ state["action_net.weight"].T + state["action_net.bias"]
    value = out["value_net"] @ state["value_net.weight"].T + state["value_net.bias"]
    return action, value


def test_legacy_shared_weights_load_into_the_large_network():
    state = legacy_state(10, shared=True)
    model = PPO("MlpPolicy", SnakeVecEnv(1, joints=10), policy_kwargs=policy_kwargs("large"), device="cpu")
    model.policy.load_state_dict(convert_legacy_state_dict(state))
    obs = np.random.default_rng(0).normal(size=(4, 22)).astype(np.float32)
    with torch.no_grad():
        action, value = legacy_forward(state, obs, shared=True)
        dist = model.policy.get_distribution(torch.as_tensor(obs))
        assert torch.allclose(dist.distribution.mean, action, atol=1e-6)
        assert torch.allclose(model.policy.predict_values(torch.as_tensor(obs)), value, atol=1e-6)


def write_legacy_zip(path, state, joints, net_arch):
    """An SB3 1.x zip as the paper's: gym spaces and schedules pickled by Python 3.8 (unreadable here)."""
    garbage = "gAWVBAAAAAAAAACMAXiULg=="  # never unpickled: the loader replaces every pickled field
    box = {":type:": "<class 'gym.spaces.box.Box'>", ":serialized:": garbage, "dtype": "float32"}
    data = {
        "policy_class": {":type:": "<class 'abc.ABCMeta'>", ":serialized:": garbage},
        "policy_kwargs": {} if net_arch is None else {"net_arch": net_arch},
        "observation_space": {**box, "shape": [2 + 2 * joints]},
        "action_space": {**box, "shape": [joints]},
        "num_timesteps": 20000000,
        "lr_schedule": {":type:": "<class 'function'>", ":serialized:": garbage},
        "clip_range": {":type:": "<class 'function'>", ":serialized:": garbage},
        "use_sde": False,
    }
    buffer = io.BytesIO()
    torch.save(state, buffer)
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("data", json.dumps(data))
        z.writestr("policy.pth", buffer.getvalue())
        z.writestr("_stable_baselines3_version", "1.0")


@pytest.mark.parametrize("shared", [False, True])
def test_load_an_sb3_1x_zip(tmp_path, shared):
    joints = 4
    state = legacy_state(joints, shared)
    path = tmp_path / "legacy.zip"
    write_legacy_zip(path, state, joints, [128, 128, {"pi": [64, 64], "vf": [64, 64]}] if shared else None)
    info = inspect_model(path)
    assert info.legacy and info.sb3_version == "1.0" and (info.observation_dim, info.action_dim) == (10, 4)
    agent = load_agent(path, preset="snakebot-gym")
    assert agent.joints == joints, "joints come from the model's action space"
    assert agent.arch == ("large" if shared else "small")
    assert agent.env_kwargs == {"joints": 4, "preset": "snakebot-gym"}
    obs = np.random.default_rng(1).normal(size=(3, 10)).astype(np.float32)
    action, _ = legacy_forward(state, obs, shared)
    expected = np.clip(action.numpy(), -1, 1)
    np.testing.assert_allclose(agent.act(obs, deterministic=True), expected, atol=1e-6)
