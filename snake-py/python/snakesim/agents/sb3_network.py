"""An SB3 zip's network, rebuilt as snakesim's ``ActorCriticPolicy`` (:mod:`snakesim.runs.policies`)
from the weights' names and shapes and the plain parts of ``policy_kwargs``: ``policy.pth`` is read
with ``torch.load(weights_only=True)``, every tensor checked (dense, floating-point, finite in
float32, of the shape the network expects) and every error one line naming the zip, the member and
the tensor."""

from __future__ import annotations

import io
import json
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from snakesim.agents.protocol import AgentError, first_line
from snakesim.agents.sb3_zip import ModelInfo, Zip
from snakesim.runs import config as runconfig

# activation_fn ("<class 'torch.nn.modules.activation.Tanh'>"); looked up in torch.nn, never unpickled.
_ACTIVATIONS = ("Tanh", "ReLU", "LeakyReLU", "ELU", "GELU", "SiLU", "Sigmoid")
_EXTRACTORS = {
    "<class 'stable_baselines3.common.torch_layers.FlattenExtractor'>",
    "<class 'snakesim.runs.policies.SharedMlp'>",
}
# Where the layers of each part of the network live in an SB3 2.x state dict (Linear, activation, ...).
_PARTS = {
    "shared": "features_extractor.shared_net",
    "pi": "mlp_extractor.policy_net",
    "vf": "mlp_extractor.value_net",
}


def sb3_policy(path: Path, archive: Zip, device: str):
    """The zip's policy as an SB3 2.x ActorCriticPolicy with snakesim's networks, and its arch label.

    The network is rebuilt from the shapes of the weights (widths of the shared trunk and of the
    heads) and the plain parts of ``policy_kwargs``; SB3 1.x weights are renamed where 1.x named them
    differently (shared layers).
    """
    import torch
    from stable_baselines3.common.policies import ActorCriticPolicy

    from snakesim.runs.policies import convert_legacy_state_dict, policy_kwargs

    info, data = archive.info, archive.data
    if data.get("use_sde"):
        raise AgentError(f"{path}: models with gSDE (use_sde) are not supported")
    where = f"{path}: member policy.pth"
    state = _weights(where, archive.weights, device)
    if info.legacy:
        state = convert_legacy_state_dict(state)
    activation = _activation(path, data.get("policy_kwargs"))
    widths = _widths(where, state, info)
    try:
        label = runconfig.arch_label(widths)
    except runconfig.ConfigError as error:
        raise AgentError(f"{path}: its network: {error}") from None
    # In float32, as the network holds them (a float64 weight of 1e300 becomes infinite there).
    state = {name: tensor.to(torch.float32) for name, tensor in state.items()}
    for name, tensor in state.items():
        if not bool(torch.isfinite(tensor).all()):
            raise AgentError(f"{where}: tensor {_tensor_name(name)} holds NaN or infinite values")
    observation_space, action_space = _spaces(info.observation_dim, info.action_dim)
    kwargs = policy_kwargs(widths)
    if activation is not None:
        kwargs["activation_fn"] = activation
    policy = ActorCriticPolicy(observation_space, action_space, lambda _: 0.0, **kwargs).to(device)
    expected = policy.state_dict()
    for name, tensor in expected.items():
        if name not in state:
            raise AgentError(
                f"{where}: the weights do not fit the network: no tensor {name} (expected shape "
                f"{list(tensor.shape)})"
            )
        if state[name].shape != tensor.shape:
            raise AgentError(
                f"{where}: the weights do not fit the network: tensor {name} has shape "
                f"{list(state[name].shape)}, expected {list(tensor.shape)}"
            )
    extra = [name for name in state if name not in expected]
    if extra:
        raise AgentError(
            f"{where}: the weights do not fit the network: tensor {_tensor_name(extra[0])} is not one of "
            f"its {len(expected)} (PPO-{label}, {info.observation_dim} observations)"
        )
    try:
        policy.load_state_dict(state)
    except RuntimeError as error:  # after the checks above, a bug here rather than the file's
        raise AgentError(f"{where}: the weights do not fit the network: {first_line(error)}") from None
    policy.set_training_mode(False)
    return policy, label


def _tensor_name(name: str) -> str:
    """A tensor's name from the file, for an error: a short dotted name as it is, anything else as
    an excerpt."""
    if re.fullmatch(r"[\w.]{1,80}", name, flags=re.ASCII):
        return name
    shown = json.dumps(name)
    return shown if len(shown) <= 24 else shown[:21] + "..."


def _torch_error(error: BaseException) -> str:
    """What went wrong in ``torch.load``, in a sentence: its weights-only unpickler's own finding
    (``Unsupported operand 103``) rather than the paragraph around it, which suggests loading the file
    unsafely."""
    text = str(error)
    if "WeightsUnpickler error:" in text:
        text = text.split("WeightsUnpickler error:", 1)[1]
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    first = lines[0].split(". ")[0].removesuffix(".") if lines else ""
    return f"{type(error).__name__}: {first[:160]}{'...' if len(first) > 160 else ''}"


def _weights(where: str, data: bytes, device: str) -> dict[str, Any]:
    """``policy.pth`` read by ``torch.load(weights_only=True)``: a state dict of dense floating-point
    tensors (AgentError naming the file, the member and the tensor otherwise)."""
    import warnings

    import torch

    try:
        with warnings.catch_warnings():
            # torch's notes on what it reads (sparse tensors, their beta state): such a tensor is
            # refused below in one line.
            warnings.simplefilter("ignore")
            state = torch.load(io.BytesIO(data), map_location=device, weights_only=True)
    except Exception as error:  # noqa: BLE001 - a corrupt policy.pth fails in torch in many ways
        raise AgentError(
            f"{where}: cannot load it with torch.load(weights_only=True): {_torch_error(error)}"
        ) from None
    if not isinstance(state, dict) or not all(
        isinstance(k, str) and isinstance(v, torch.Tensor) for k, v in state.items()
    ):
        raise AgentError(f"{where}: cannot load it as a policy: it holds no state dict (tensors by name)")
    for name, tensor in state.items():
        shown = _tensor_name(name)
        if tensor.layout != torch.strided:
            layout = str(tensor.layout).removeprefix("torch.")
            raise AgentError(f"{where}: tensor {shown} is a {layout} tensor; a policy's weights are dense")
        if tensor.device.type == "meta":
            raise AgentError(f"{where}: tensor {shown} holds no values (a meta tensor)")
        if not tensor.is_floating_point():
            dtype = str(tensor.dtype).removeprefix("torch.")
            raise AgentError(f"{where}: tensor {shown} holds {dtype} values, not floating-point weights")
    return state


def _activation(path: Path, kwargs: Any):
    """policy_kwargs' activation_fn as a torch.nn class (None: SB3's default, Tanh), and a check that
    the features extractor is one snakesim builds; read from the JSON that SB3 writes beside a
    pickled entry, never from the pickle."""
    import torch

    if not isinstance(kwargs, Mapping):
        return None
    extractor = kwargs.get("features_extractor_class")
    if extractor is not None and extractor not in _EXTRACTORS:
        raise AgentError(f"{path}: unsupported features extractor {str(extractor)[:80]}")
    name = kwargs.get("activation_fn")
    if name is None:
        return None
    match = re.fullmatch(r"<class 'torch\.nn\.modules\.activation\.(\w+)'>", str(name))
    if not match or match.group(1) not in _ACTIVATIONS:
        raise AgentError(f"{path}: unsupported activation_fn {str(name)[:80]}")
    return getattr(torch.nn, match.group(1))


def _widths(path: Path | str, state: Mapping[str, Any], info: ModelInfo) -> dict[str, list[int]]:
    """The widths of the shared trunk and the heads, read from the weights' shapes, checked layer by
    layer (each Linear takes what the one before gives) before anything is built from them."""
    widths: dict[str, list[int]] = {}
    trunk_out = info.observation_dim
    for part, prefix in _PARTS.items():
        sizes: list[int] = []
        width = info.observation_dim if part == "shared" else trunk_out
        while f"{prefix}.{2 * len(sizes)}.weight" in state:
            weight = state[f"{prefix}.{2 * len(sizes)}.weight"]
            if weight.dim() != 2 or weight.shape[1] != width:
                raise AgentError(
                    f"{path}: the weights do not fit the network: {prefix}.{2 * len(sizes)}.weight has "
                    f"shape {list(weight.shape)}, expected [*, {width}]"
                )
            width = int(weight.shape[0])
            sizes.append(width)
        widths[part] = sizes
        if part == "shared" and sizes:
            trunk_out = sizes[-1]
    # SB3 2.x registers a shared trunk under three names; they must be one set of weights.
    for key, value in state.items():
        owner, _, rest = key.partition(".")
        if owner in ("pi_features_extractor", "vf_features_extractor"):
            same = state.get(f"features_extractor.{rest}")
            if same is None or same.shape != value.shape or not bool((same == value).all()):
                raise AgentError(f"{path}: separate policy and value trunks are not supported")
    if not widths["pi"] or not widths["vf"]:
        raise AgentError(f"{path}: the weights do not fit the network: no policy and value layers")
    return widths


def _spaces(obs_dim: int, act_dim: int):
    from gymnasium import spaces

    return (
        spaces.Box(-np.inf, np.inf, (obs_dim,), dtype=np.float32),
        spaces.Box(-1.0, 1.0, (act_dim,), dtype=np.float32),
    )
