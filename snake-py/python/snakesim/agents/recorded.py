"""What a model records about its env, as every reader uses it: the env keywords agreed with the
caller's, checked against the model's sizes; its ``steer_assist``; the notes loading prints."""

from __future__ import annotations

import json
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from snakesim.agents.protocol import AgentError, Keyword


def note(lines: list[str], overrides: Mapping[str, Any] | None = None) -> None:
    """Tells the user what loading found (a robot file that changed since training), one line each.
    Where ``overrides`` replace the robot (world) the note is about (``snakesim evaluate --robot``),
    it says that the given one runs, not the record."""
    for line in lines:
        for key in ("robot", "world"):
            ending = f"; the {key} recorded in the model is used"
            given = (overrides or {}).get(key)
            if line.endswith(ending) and isinstance(given, (str, Path)):
                given_one = f"the {key} file given, {given}, is used, not the recorded one"
                line = f"{line.removesuffix(ending)}; {given_one}"
        print(f"note: {line}", file=sys.stderr)


def bind_assist(where: Path | str, assist: Any, env_kwargs: Mapping[str, Any]) -> Any:
    """A recorded ``steer_assist`` (JSON text or a mapping) bound to the env of ``env_kwargs`` (a
    ``_core.SteerAssist``), or None when there is none."""
    from snakesim import _core
    from snakesim.envs.config import env_config

    if assist is None:
        return None
    text = assist if isinstance(assist, str) else json.dumps(assist)
    try:
        return _core.SteerAssist.from_json(text, env_config(**env_kwargs))
    except (TypeError, ValueError) as error:
        raise AgentError(f"{where}: {error}") from None


def agreed_env(
    where: Path | str,
    recorded: dict[str, Any],
    joints: int | None,
    preset: str | None,
    overrides: Mapping[str, Any] | None,
) -> dict[str, Any]:
    """The recorded env keywords, with ``overrides``; AgentError when ``joints`` or ``preset`` are
    given and differ from the recorded ones."""
    for name, given in (("joints", joints), ("preset", preset)):
        if given is not None and given != recorded.setdefault(name, given):
            raise AgentError(f"{where} was trained with {name} {recorded[name]}, not {given}")
    return {**recorded, **(overrides or {})}


def check_env(
    model: Path, env_kwargs: dict[str, Any], obs_dim: int, act_dim: int, hint: tuple[str | Keyword, ...] = ()
) -> None:
    """AgentError unless the env of ``env_kwargs`` has the model's observation and action sizes;
    ``hint`` ends its message (it may name a keyword argument of the loader)."""
    from snakesim.envs.env import make_env

    try:
        probe = make_env(**env_kwargs)
    except (TypeError, ValueError) as error:
        raise AgentError(str(error)) from None
    has = (probe.observation_space.shape[0], probe.action_space.shape[0])
    if has != (obs_dim, act_dim):
        raise AgentError(
            f"{model} expects {obs_dim} observations and {act_dim} actions, but the env "
            f"({probe.joints} joints) has {has[0]} and {has[1]}",
            *hint,
        )
