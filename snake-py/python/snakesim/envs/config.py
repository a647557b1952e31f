"""Keyword arguments of the envs. Their defaults and their checks live in one place, snake-rl's
configuration (Rust): this module only turns Python values into JSON for it. Errors name the keyword
(``goal[0]: invalid type: boolean ...``); a value of the wrong type raises TypeError, any other bad
value ValueError.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from snakesim import _core
from snakesim.limits import LIMITS

#: Every SnakeEnv keyword with its default (``snake``, the preset's physical parameters, aside).
ENV_DEFAULTS: dict[str, Any] = json.loads(_core.env_keyword_defaults("paper"))
#: The same for the goal-reaching task (SnakeGoalEnv, ``snakesim/SnakeGoal-v0``).
GOAL_ENV_DEFAULTS: dict[str, Any] = json.loads(_core.env_keyword_defaults("goal"))
#: The same for the peg-field task (SnakePegsEnv, ``snakesim/SnakePegs-v0``).
PEGS_ENV_DEFAULTS: dict[str, Any] = json.loads(_core.env_keyword_defaults("pegs"))
#: The same for the rough-ground task (SnakeRoughEnv, ``snakesim/SnakeRough-v0``).
ROUGH_ENV_DEFAULTS: dict[str, Any] = json.loads(_core.env_keyword_defaults("rough"))
#: The same for the swimming task (SnakeSwimEnv, ``snakesim/SnakeSwim-v0``).
SWIM_ENV_DEFAULTS: dict[str, Any] = json.loads(_core.env_keyword_defaults("swim"))
#: Keywords holding a mapping of overrides; None means the task's defaults.
TABLE_KEYWORDS = ("start", "reward", "snake", "action", "terrain", "height_map")
#: Every keyword an env accepts: ``task`` ("paper" or "goal") picks the defaults the others override.
ENV_KEYWORDS = ("task", *ENV_DEFAULTS, *(k for k in TABLE_KEYWORDS if k not in ENV_DEFAULTS))
PRESETS: tuple[str, ...] = tuple(_core.PRESETS)


def plain(value: Any, where: str) -> Any:
    """``value`` as JSON-ready Python: numpy scalars and arrays, tuples and mappings unwrapped; a
    non-finite number raises ValueError naming ``where``."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{where}: must be finite, got {value}")
    if isinstance(value, Mapping):
        return {str(k): plain(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"{where}: expected a number, string, list or mapping, got {type(value).__name__}")


def action_array(action: Any) -> np.ndarray:
    """An action (or a batch) as the core takes it: float32 and float64 as they are, integers as
    float64, half floats as float32; any other dtype is left for the core to refuse (TypeError)."""
    array = np.asarray(action)
    if array.dtype.kind in "iu":
        return array.astype(np.float64)
    if array.dtype == np.float16:
        return array.astype(np.float32)
    return array


def env_config(**kwargs: Any) -> str:
    """The JSON of SnakeEnv keywords for the Rust side, which checks them. A table keyword (``start``,
    ``reward``, ``snake``) of None means its defaults."""
    unknown = sorted(set(kwargs) - set(ENV_KEYWORDS))
    if unknown:
        raise TypeError(
            f"unexpected keyword{'s' if len(unknown) > 1 else ''} {', '.join(unknown)} "
            f"(expected: {', '.join(ENV_KEYWORDS)})"
        )
    table = {
        key: plain(value, key)
        for key, value in kwargs.items()
        if not (key in TABLE_KEYWORDS and value is None)
    }
    if "max_episode_steps" in table and table["max_episode_steps"] is None:
        # No limit of the env's own: a TimeLimit wrapper truncates (what gymnasium.make adds).
        table["max_episode_steps"] = LIMITS["episode_steps"]
    return json.dumps(table)


def file_keyword(value: Any) -> Any:
    """A ``robot`` or ``world`` keyword as the env keeps it: None, a path as a string, or a record of
    the file's texts (``{"path": ..., "files": {name: text}}``, what a model records) as it is."""
    if value is None or isinstance(value, Mapping):
        return value
    return os.fspath(value)


def file_label(value: Any) -> str:
    """A ``robot`` or ``world`` keyword in words: its path, or a record's path marked as recorded."""
    if isinstance(value, Mapping):
        return f"{value.get('path')} (as recorded in the model)"
    return str(value)


def env_file_records(env_kwargs: Mapping[str, Any]) -> dict[str, Any] | None:
    """The texts of the robot and world files of the env of ``env_kwargs``, as a model records them
    (``{"robot": {"path": ..., "files": {name: text}}, "world": ...}``; docs/formats.md), or None
    when the env has neither."""
    text = _core.env_file_records(env_config(**env_kwargs))
    return None if text is None else json.loads(text)


def apply_env_files(env_kwargs: Mapping[str, Any], records: Any) -> tuple[dict[str, Any], list[str]]:
    """A model's recorded files applied to its env keywords: the keywords with each robot or world
    file that no longer holds the recorded texts replaced by its record, and a note for each.
    ValueError (one line) for a record that does not fit the keywords."""
    text, notes = _core.apply_env_files(
        json.dumps(plain(dict(env_kwargs), "env")), json.dumps(plain(records, "env_files"))
    )
    return json.loads(text), list(notes)


def observation_slice(structure: Mapping[str, int], name: str) -> slice:
    """The indices of the part ``name`` of an observation of ``structure`` (an env's
    ``observation_structure``: name -> size, in order): ``obs[..., observation_slice(s, "goal_vector")]``.
    A name the structure lacks raises KeyError naming those it has."""
    start = 0
    for part, size in structure.items():
        if part == name:
            return slice(start, start + size)
        start += size
    raise KeyError(f"the observation has no {name!r} (it has: {', '.join(structure)})")
