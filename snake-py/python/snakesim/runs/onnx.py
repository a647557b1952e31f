"""A policy as an ONNX graph, for running on the robot: ``snakesim export MODEL --onnx policy.onnx``.

The graph computes, for a batch of raw observations, what a loaded agent's ``act(obs,
deterministic=True)`` computes (:mod:`snakesim.agents.protocol`: each agent gives its ``actor``), for
native models and SB3 zips alike:

1. when the model normalises observations, ``clip((obs - mean) / sqrt(var + epsilon), -clip, clip)``
   in float64, then float32: the native policy's ``RunningMeanStd::normalize`` (snake-rl's
   ``normalize.rs``: epsilon 1e-8, clip 10) and SB3's ``VecNormalize.normalize_obs`` (its own
   ``epsilon`` and ``clip_obs``) both compute it so;
2. the actor: the shared trunk (tanh layers, PPO-large's), the policy head (tanh; an SB3 model's own
   activation) and ``action_net``: the Gaussian's mean (no value network, no ``log_std``);
3. the mean clipped to the action space ([-1, 1]), as SB3's ``predict`` and the native policy clip it.

Input ``observation`` (float32, ``[batch, obs_dim]``, the batch dynamic), output ``action`` (float32,
``[batch, act_dim]``); opset 17 (ONNX Runtime 1.13 and newer). The graph is built with ``onnx.helper``
from the numpy weights the loader already holds: exporting a native model needs no torch. The model's
metadata (``metadata_props``) records what a control loop needs: the observation's parts in order, the
action mode and scale, the env keywords. See docs/deploy.md.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from snakesim.files import write_atomically

#: The graph's input and output names.
INPUT = "observation"
OUTPUT = "action"
#: The ONNX operator set and IR version the graph is written for (ONNX Runtime 1.13+ reads them).
OPSET = 17
IR_VERSION = 8
#: The native policy's normalisation (snake-rl/src/normalize.rs, ``EPSILON`` and ``CLIP``: SB3's
#: ``VecNormalize`` defaults); the test against the native policy's actions guards the two numbers.
NATIVE_EPSILON = 1e-8
NATIVE_CLIP = 10.0
#: Keys of the model's ``metadata_props``.
METADATA_PREFIX = "snakesim."

# SB3 activations (torch.nn class names, as snakesim.agents.sb3_network accepts them) -> ONNX.
_ACTIVATIONS = ("Tanh", "ReLU", "LeakyReLU", "ELU", "GELU", "SiLU", "Sigmoid")


class ExportError(ValueError):
    """A policy that cannot be written as ONNX; the message says why."""


@dataclasses.dataclass(frozen=True)
class Dense:
    """One linear layer ``x @ weight.T + bias`` and the activation after it (None: none)."""

    weight: np.ndarray  # float32 [outputs, inputs]
    bias: np.ndarray  # float32 [outputs]
    activation: str | None = None
    alpha: float = 0.0  # LeakyReLU's negative slope, ELU's alpha


@dataclasses.dataclass(frozen=True)
class Normalization:
    """``clip((obs - mean) / sqrt(var + epsilon), -clip, clip)``, in float64."""

    mean: np.ndarray  # float64 [obs_dim]
    var: np.ndarray  # float64 [obs_dim]
    epsilon: float
    clip: float


@dataclasses.dataclass(frozen=True)
class Actor:
    """The deterministic action's computation, as numbers: what the graph is built from."""

    obs_dim: int
    layers: tuple[Dense, ...]  # the trunk and the policy head, then action_net (no activation)
    normalization: Normalization | None
    low: np.ndarray  # float32 [act_dim], the action space's bounds
    high: np.ndarray

    @property
    def act_dim(self) -> int:
        return int(self.layers[-1].weight.shape[0])


# -- the actor of a loaded agent --------------------------------------------------------------------
def actor_of(agent: Any) -> Actor:
    """The actor of a loaded agent (:func:`snakesim.agents.load_agent`): a native model or an SB3 one."""
    if getattr(agent, "steer_assist", None) is not None:
        # Its actions are the policy's composed with baseline:steer's, which the graph does not hold.
        raise ExportError(
            f"{agent.path} was trained with steer_assist (baseline:steer shares its actions): an ONNX "
            "graph of its policy alone would not act as it does; export --sb3 keeps the assist"
        )
    # The agent knows what it is: a model answers with its actor, a hand-made controller refuses.
    return agent.actor()


def native_actor(policy: Any, normalization: Normalization | None) -> Actor:
    """A ``_core.NativePolicy``: tanh layers under SB3's tensor names (snake-rl's ``nn::network``),
    after ``normalization`` (the agent's, :meth:`snakesim.agents.native.NativeAgent.normalization`)."""
    tensors = policy.tensors()
    arch = policy.net_arch

    def take(name: str, activation: str | None) -> Dense:
        try:
            weight, bias = tensors[f"{name}.weight"], tensors[f"{name}.bias"]
        except KeyError:
            raise ExportError(f"{policy.path}: the model has no tensor {name}") from None
        return Dense(np.asarray(weight, np.float32), np.asarray(bias, np.float32), activation)

    layers = [take(f"features_extractor.shared_net.{2 * i}", "Tanh") for i in range(len(arch["shared"]))]
    layers += [take(f"mlp_extractor.policy_net.{2 * i}", "Tanh") for i in range(len(arch["pi"]))]
    layers.append(take("action_net", None))
    ones = np.ones(policy.act_dim, np.float32)
    return _checked(Actor(int(policy.obs_dim), tuple(layers), normalization, -ones, ones), policy.path)


def sb3_actor(policy: Any, normalization: Normalization | None) -> Actor:
    """An SB3 ``ActorCriticPolicy`` as the loader builds it: the policy's features extractor (SB3's
    ``FlattenExtractor`` or snakesim's ``SharedMlp``), ``mlp_extractor.policy_net``, ``action_net``;
    after ``normalization`` (a ``VecNormalize``'s statistics, epsilon and clip when it normalises
    observations: :meth:`snakesim.agents.sb3.SB3Agent.normalization`)."""
    if getattr(policy, "squash_output", False) or getattr(policy, "use_sde", False):
        raise ExportError("SB3 policies with squashed outputs or gSDE are not supported")
    extractor = getattr(policy, "pi_features_extractor", None)
    if extractor is None:
        extractor = policy.features_extractor
    layers: list[Dense] = []
    trunk = getattr(extractor, "shared_net", None)
    if trunk is not None:
        layers += _sequential(trunk)
    elif type(extractor).__name__ != "FlattenExtractor":
        raise ExportError(f"unsupported features extractor {type(extractor).__name__}")
    layers += _sequential(policy.mlp_extractor.policy_net)
    layers += _sequential([policy.action_net])
    if layers[-1].activation is not None:
        raise ExportError("the policy's action_net ends in an activation")
    space = policy.action_space
    low, high = np.asarray(space.low, np.float32), np.asarray(space.high, np.float32)
    obs_dim = int(np.prod(policy.observation_space.shape))
    return _checked(Actor(obs_dim, tuple(layers), normalization, low, high), "the SB3 policy")


def _sequential(modules: Any) -> list[Dense]:
    """torch ``Linear`` layers, each with the activation module that follows it (read by class name and
    attributes; nothing here imports torch)."""
    layers: list[Dense] = []
    for module in modules:
        name = type(module).__name__
        if name == "Linear":
            weight = module.weight.detach().cpu().numpy().astype(np.float32)
            bias = module.bias
            bias = np.zeros(weight.shape[0], np.float32) if bias is None else bias.detach().cpu().numpy()
            layers.append(Dense(weight, np.asarray(bias, np.float32)))
        elif name in _ACTIVATIONS:
            if not layers or layers[-1].activation is not None:
                raise ExportError(f"an activation ({name}) that follows no linear layer")
            alpha = 0.0
            if name == "LeakyReLU":
                alpha = float(module.negative_slope)
            elif name == "ELU":
                alpha = float(module.alpha)
            elif name == "GELU" and getattr(module, "approximate", "none") != "none":
                raise ExportError("GELU with the tanh approximation is not supported")
            layers[-1] = dataclasses.replace(layers[-1], activation=name, alpha=alpha)
        elif name not in ("Flatten", "Identity"):
            raise ExportError(f"unsupported layer {name} in the policy network")
    return layers


def _checked(actor: Actor, where: str) -> Actor:
    """ExportError unless each layer takes what the one before gives and every number is finite."""
    width = actor.obs_dim
    for dense in actor.layers:
        if (
            dense.weight.ndim != 2
            or dense.weight.shape[1] != width
            or dense.bias.shape != dense.weight.shape[:1]
        ):
            raise ExportError(
                f"{where}: its layers do not chain (a weight of shape {list(dense.weight.shape)})"
            )
        if not (np.isfinite(dense.weight).all() and np.isfinite(dense.bias).all()):
            raise ExportError(f"{where}: its weights hold NaN or infinite values")
        width = dense.weight.shape[0]
    norm = actor.normalization
    if norm is not None:
        if norm.mean.shape != (actor.obs_dim,) or norm.var.shape != (actor.obs_dim,):
            raise ExportError(f"{where}: observation statistics of the wrong size")
        finite = np.isfinite(norm.mean).all() and np.isfinite(norm.var).all() and math.isfinite(norm.epsilon)
        if not finite or (norm.var < 0).any() or norm.epsilon < 0 or not norm.clip > 0:
            raise ExportError(f"{where}: observation statistics that are not finite and positive")
    if actor.low.shape != (actor.act_dim,) or actor.high.shape != (actor.act_dim,):
        raise ExportError(f"{where}: an action space of the wrong size")
    return actor


# -- the graph --------------------------------------------------------------------------------------
def _onnx():
    try:
        import onnx
    except ImportError:
        raise ImportError(
            "snakesim export --onnx needs the Python module 'onnx' (a dependency of snakesim): "
            "pip install onnx"
        ) from None
    return onnx


class _Builder:
    """Nodes and initializers, named in order."""

    def __init__(self, onnx: Any) -> None:
        self.onnx = onnx
        self.nodes: list[Any] = []
        self.initializers: list[Any] = []
        self._count = 0

    def name(self, stem: str) -> str:
        self._count += 1
        return f"{stem}_{self._count}"

    def constant(self, stem: str, array: np.ndarray) -> str:
        name = self.name(stem)
        self.initializers.append(self.onnx.numpy_helper.from_array(np.ascontiguousarray(array), name))
        return name

    def node(self, op: str, inputs: list[str], stem: str | None = None, **attributes: Any) -> str:
        out = self.name(stem or op.lower())
        self.nodes.append(
            self.onnx.helper.make_node(op, inputs, [out], name=f"{op}_{self._count}", **attributes)
        )
        return out

    def activation(self, x: str, dense: Dense) -> str:
        activation = dense.activation
        if activation == "Tanh":
            return self.node("Tanh", [x])
        if activation == "ReLU":
            return self.node("Relu", [x])
        if activation == "LeakyReLU":
            return self.node("LeakyRelu", [x], alpha=dense.alpha)
        if activation == "ELU":
            return self.node("Elu", [x], alpha=dense.alpha)
        if activation == "Sigmoid":
            return self.node("Sigmoid", [x])
        if activation == "SiLU":  # x * sigmoid(x)
            return self.node("Mul", [x, self.node("Sigmoid", [x])], "silu")
        if activation == "GELU":  # torch's exact GELU: x / 2 * (1 + erf(x / sqrt(2)))
            scaled = self.node("Mul", [x, self.constant("inv_sqrt2", np.array(1 / math.sqrt(2), np.float32))])
            erf = self.node("Erf", [scaled])
            one = self.node("Add", [erf, self.constant("one", np.array(1.0, np.float32))])
            half = self.node("Mul", [x, self.constant("half", np.array(0.5, np.float32))])
            return self.node("Mul", [half, one], "gelu")
        raise ExportError(f"unsupported activation {activation}")


def build_model(actor: Actor, metadata: Mapping[str, str] | None = None, doc: str = "") -> Any:
    """The ONNX model (an ``onnx.ModelProto``, checked) of ``actor``; ``metadata`` goes into its
    ``metadata_props``."""
    onnx = _onnx()
    helper, TensorProto = onnx.helper, onnx.TensorProto
    b = _Builder(onnx)
    x = INPUT
    norm = actor.normalization
    if norm is not None:
        # In float64, as both the native policy and VecNormalize normalise; then float32, as they hand
        # the result to the network.
        wide = b.node("Cast", [x], "obs_f64", to=TensorProto.DOUBLE)
        centred = b.node("Sub", [wide, b.constant("obs_mean", norm.mean)])
        scaled = b.node("Div", [centred, b.constant("obs_std", np.sqrt(norm.var + norm.epsilon))])
        clip = np.float64(norm.clip)
        clipped = b.node("Clip", [scaled, b.constant("clip_low", -clip), b.constant("clip_high", clip)])
        x = b.node("Cast", [clipped], "obs_normalized", to=TensorProto.FLOAT)
    for i, dense in enumerate(actor.layers):
        last = i == len(actor.layers) - 1
        w = b.constant("action_net_weight" if last else f"layer{i}_weight", dense.weight)
        bias = b.constant("action_net_bias" if last else f"layer{i}_bias", dense.bias)
        x = b.node("Gemm", [x, w, bias], "mean" if last else f"layer{i}", transB=1)
        if dense.activation is not None:
            x = b.activation(x, dense)
    low, high = b.constant("action_low", actor.low), b.constant("action_high", actor.high)
    # Clip takes scalar bounds; per-dimension bounds (all -1 and 1 here) need Max and Min.
    b.nodes.append(
        helper.make_node("Min", [b.node("Max", [x, low]), high], [OUTPUT], name="clip_to_action_space")
    )
    graph = helper.make_graph(
        b.nodes,
        "snakesim_policy",
        [helper.make_tensor_value_info(INPUT, TensorProto.FLOAT, ["batch", actor.obs_dim])],
        [helper.make_tensor_value_info(OUTPUT, TensorProto.FLOAT, ["batch", actor.act_dim])],
        b.initializers,
        doc_string=doc,
    )
    model = helper.make_model(
        graph,
        opset_imports=[helper.make_opsetid("", OPSET)],
        ir_version=IR_VERSION,
        producer_name="snakesim",
        doc_string=doc,
    )
    helper.set_model_props(model, dict(metadata or {}))
    try:
        onnx.checker.check_model(model, full_check=True)
    except onnx.checker.ValidationError as error:  # a bug here, not the user's input
        raise ExportError(f"the ONNX graph does not check: {str(error).splitlines()[0][:200]}") from None
    return model


#: The keys of the env's `action` table that each action mode reads: a joints-mode model's file lists no
#: gait ranges, which its actions never pass through.
ACTION_KEYS = {"joints": (), "gait": ("steering", "amplitude", "frequency"), "residual": ("residual_scale",)}


def action_metadata(action: dict[str, Any]) -> dict[str, Any]:
    """The action mode and the ranges that mode uses (`snakesim.action`)."""
    mode = action["mode"]
    return {"mode": mode, **{key: action[key] for key in ACTION_KEYS[mode]}}


def metadata_of(agent: Any, actor: Actor) -> dict[str, str]:
    """What a control loop needs besides the graph: the observation's parts in order (the env's
    ``observation_structure``), the action mode and scale, the control period, the env keywords, the
    normalisation."""
    from snakesim.envs.env import make_env

    env = make_env(**agent.env_kwargs)
    norm = actor.normalization
    return {
        METADATA_PREFIX + "observation_structure": json.dumps(env.observation_structure),
        METADATA_PREFIX + "action": json.dumps(action_metadata(env.config["action"])),
        METADATA_PREFIX + "action_scale": json.dumps(env.config["action_scale"]),
        # One action every this many physics steps (of 1/240 s): the control period.
        METADATA_PREFIX + "physics_steps_per_env_step": json.dumps(env.config["physics_steps_per_env_step"]),
        METADATA_PREFIX + "env_kwargs": json.dumps(agent.env_kwargs, default=str),
        METADATA_PREFIX + "policy": json.dumps(agent.label),
        METADATA_PREFIX + "normalization": json.dumps(
            None if norm is None else {"epsilon": norm.epsilon, "clip": norm.clip}
        ),
    }


def to_onnx_bytes(agent: Any) -> bytes:
    """The serialised ONNX model of a loaded agent (see the module's docstring)."""
    actor = actor_of(agent)
    normalized = "observations normalised inside, " if actor.normalization is not None else ""
    doc = (
        f"snakesim {agent.label} ({agent.body}): {INPUT} [batch, {actor.obs_dim}] float32 -> {OUTPUT} "
        f"[batch, {actor.act_dim}] float32, {normalized}the deterministic action clipped to the action space"
    )
    return build_model(actor, metadata_of(agent, actor), doc).SerializeToString()


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Writes ``data`` to ``path`` whole or not at all (:func:`snakesim.files.write_atomically`)."""
    out = Path(path)
    write_atomically(out, lambda tmp: Path(tmp).write_bytes(data))
    return out


def to_onnx(agent: Any, path: str | os.PathLike) -> Path:
    """Writes the agent's policy as an ONNX model to ``path``; returns it."""
    return write_bytes(path, to_onnx_bytes(agent))
