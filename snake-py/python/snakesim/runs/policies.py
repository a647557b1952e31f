"""The paper's two PPO networks in Stable-Baselines3 2.x.

- PPO-small: SB3's default ``MlpPolicy``, separate policy and value networks of [64, 64] (tanh).
- PPO-large: the paper's ``net_arch=[128, 128, dict(pi=[64, 64], vf=[64, 64])]`` (SB3 1.x): two layers
  of 128 shared by the policy and the value function, then separate [64, 64] heads. SB3 1.8 removed
  shared layers from ``net_arch``; here they are a features extractor (:class:`SharedMlp`) shared by
  both heads (``share_features_extractor=True``), which is the same network with the same number of
  parameters, initialised the same way (orthogonal, gain sqrt(2), as SB3 initialises both).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from gymnasium import spaces

from snakesim import extras

extras.require("sb3", "snakesim.runs.policies (the paper's networks in Stable-Baselines3)")

import torch  # noqa: E402
from stable_baselines3.common.preprocessing import get_flattened_obs_dim  # noqa: E402
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor  # noqa: E402
from torch import nn  # noqa: E402

HEADS = {"pi": [64, 64], "vf": [64, 64]}
SHARED = [128, 128]


class SharedMlp(BaseFeaturesExtractor):
    """Flatten, then Linear + Tanh layers (default two of 128): the shared trunk of PPO-large."""

    def __init__(self, observation_space: spaces.Space, hidden: Sequence[int] = (128, 128)) -> None:
        hidden = [int(h) for h in hidden]
        if not hidden or min(hidden) < 1:
            raise ValueError(f"hidden must be a non-empty list of positive sizes, got {hidden!r}")
        super().__init__(observation_space, features_dim=hidden[-1])
        self.flatten = nn.Flatten()
        layers: list[nn.Module] = []
        width = get_flattened_obs_dim(observation_space)
        for size in hidden:
            layers += [nn.Linear(width, size), nn.Tanh()]
            width = size
        # Named as SB3 1.x's MlpExtractor named its shared layers, so 1.x weights map one to one.
        self.shared_net = nn.Sequential(*layers)

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        return self.shared_net(self.flatten(observations))


def policy_kwargs(
    arch: str | Mapping[str, Sequence[int]], shared: Sequence[int] = SHARED, log_std_init: float = 0.0
) -> dict[str, Any]:
    """``policy_kwargs`` of SB3's ``PPO("MlpPolicy", ...)`` for a run configuration's ``arch``: the paper's
    ``small`` or ``large`` network (``shared``: the large trunk's widths), or a mapping of widths
    ``{shared, pi, vf}`` (a part left out takes small's: no trunk, [64, 64] heads). ``log_std_init`` is
    SB3's, the initial log standard deviation of the action noise."""
    if isinstance(arch, Mapping):
        unknown = set(arch) - {"shared", *HEADS}
        if unknown:
            raise ValueError(f"arch: unknown keys {sorted(unknown)} (expected shared, pi, vf)")
        shared = [int(w) for w in arch.get("shared", [])]
        heads = {key: [int(w) for w in arch.get(key, value)] for key, value in HEADS.items()}
    elif arch in ("small", "large"):
        shared = list(shared) if arch == "large" else []
        heads = {key: list(value) for key, value in HEADS.items()}
    else:
        raise ValueError(f"unknown arch {arch!r} (expected small, large or a mapping of widths)")
    kwargs: dict[str, Any] = {"net_arch": heads, "log_std_init": float(log_std_init)}
    if shared:
        kwargs |= {
            "features_extractor_class": SharedMlp,
            "features_extractor_kwargs": {"hidden": shared},
            "share_features_extractor": True,
        }
    return kwargs


def parameter_count(module: nn.Module) -> int:
    """Trainable parameters, each shared tensor counted once."""
    return sum(p.numel() for p in module.parameters() if p.requires_grad)


def parse_legacy_net_arch(net_arch: Any) -> tuple[str, list[int]]:
    """SB3 1.x's ``net_arch`` -> (``small`` or ``large``, shared layer sizes); ValueError otherwise.

    1.x wrote ``[int, ..., dict(pi=[...], vf=[...])]``: the ints are shared layers. Only the paper's
    heads (pi and vf of [64, 64]) are supported.
    """
    if net_arch is None or net_arch == []:
        return "small", []
    items = list(net_arch) if isinstance(net_arch, (list, tuple)) else [net_arch]
    shared = [x for x in items if isinstance(x, int) and not isinstance(x, bool)]
    heads = [x for x in items if isinstance(x, Mapping)]
    if len(shared) + len(heads) != len(items) or len(heads) > 1 or (heads and items[-1] is not heads[0]):
        raise ValueError(f"unsupported SB3 1.x net_arch {net_arch!r}")
    if heads and {k: list(v) for k, v in heads[0].items()} != HEADS:
        raise ValueError(f"unsupported SB3 1.x net_arch {net_arch!r}: heads other than pi/vf [64, 64]")
    if not heads and shared:
        raise ValueError(f"unsupported SB3 1.x net_arch {net_arch!r}: no separate pi/vf heads")
    return ("large", shared) if shared else ("small", [])


def convert_legacy_state_dict(state: Mapping[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """An SB3 1.x ``ActorCriticPolicy`` state dict -> the SB3 2.x one of :func:`policy_kwargs`.

    1.x kept shared layers in ``mlp_extractor.shared_net``; here they live in the shared features
    extractor, which SB3 2.x registers under three names (``features_extractor``,
    ``pi_features_extractor``, ``vf_features_extractor``), all one module.
    """
    out: dict[str, torch.Tensor] = {}
    for key, value in state.items():
        prefix = "mlp_extractor.shared_net."
        if key.startswith(prefix):
            rest = key[len(prefix) :]
            for owner in ("features_extractor", "pi_features_extractor", "vf_features_extractor"):
                out[f"{owner}.shared_net.{rest}"] = value
        else:
            out[key] = value
    return out
