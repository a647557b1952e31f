"""Stable-Baselines3 zips (2.x, and the paper's 1.x) as data: the members loading reads, ``data`` as
plain JSON (no entry marked ``":serialized:"`` is ever unpickled) and ``policy.pth`` as bytes, each
refused when its uncompressed size is over its cap (docs/formats.md)."""

from __future__ import annotations

import dataclasses
import io
import json
import os
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from snakesim.agents.protocol import AgentError
from snakesim.files import FileError, check_size, read_bytes
from snakesim.limits import LIMITS

#: The entry of an SB3 zip's ``data`` where ``snakesim export`` records the env keywords (plain JSON).
EXPORTED_ENV_KEY = "snakesim_env_kwargs"
#: The entry where it records a native model's ``steer_assist`` (plain JSON), when it has one.
EXPORTED_ASSIST_KEY = "snakesim_steer_assist"
#: The entry where snakesim's SB3 trainer and ``snakesim export`` record the texts of the env's robot
#: and world files (plain JSON, a native model's ``env_files``: docs/formats.md).
RECORDED_FILES_KEY = "snakesim_env_files"

# Largest observation or action length a model may declare (a snake of MAX_JOINTS joints has ~1000).
_MAX_SPACE_SIZE = LIMITS["space_size"]


@dataclasses.dataclass
class ModelInfo:
    """What a zip's ``data`` tells without loading it."""

    sb3_version: str
    observation_dim: int
    action_dim: int
    legacy: bool  # saved by SB3 1.x with gym's spaces
    num_timesteps: int | None


@dataclasses.dataclass
class Zip:
    """The members of an SB3 zip that loading reads: ``data`` as plain JSON (no entry unpickled) and
    ``policy.pth`` as bytes."""

    info: ModelInfo
    data: dict[str, Any]
    weights: bytes


def _member(archive: zipfile.ZipFile, name: str, limit: str, path: Path) -> bytes:
    # The sizes in the zip's directory bound what is decompressed: zipfile stops at the stated size
    # (and fails the CRC when the data is longer), so a zip bomb is refused before it is inflated.
    check_size(archive.getinfo(name).file_size, limit, f"{path}: member {name}")
    return archive.read(name)


def read_zip(path: Path) -> Zip:
    """The zip's ``data`` and ``policy.pth``, read once; AgentError when it is not an SB3 model."""
    try:
        raw = read_bytes(path, "model_bytes")
    except FileError as error:
        raise AgentError(str(error)) from None
    except FileNotFoundError:
        raise AgentError(f"{path} does not exist") from None
    except IsADirectoryError:
        raise AgentError(f"{path} is not a Stable-Baselines3 model zip") from None
    except OSError as error:
        raise AgentError(f"cannot read {path}: {error.strerror or error}") from None
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as archive:
            names = set(archive.namelist())
            if "data" not in names or "policy.pth" not in names:
                raise AgentError(f"{path} is not a Stable-Baselines3 model (no data/policy.pth)")
            data = json.loads(_member(archive, "data", "config_bytes", path))
            weights = _member(archive, "policy.pth", "model_bytes", path)
            version = "unknown"
            if "_stable_baselines3_version" in names:
                version = _member(archive, "_stable_baselines3_version", "config_bytes", path).decode()
                version = version.strip()
    except FileError as error:
        raise AgentError(str(error)) from None
    except AgentError:
        raise
    except (zipfile.BadZipFile, zlib.error, EOFError, NotImplementedError, RuntimeError, ValueError):
        # A damaged directory or member, an unknown compression, an encrypted member, bad JSON or text.
        raise AgentError(f"{path} is not a Stable-Baselines3 model zip") from None
    if not isinstance(data, dict):
        raise AgentError(f"{path} is not a Stable-Baselines3 model zip (its data is not a mapping)")
    return Zip(_model_info(path, data, version[:40]), data, weights)


def _model_info(path: Path, data: dict[str, Any], version: str) -> ModelInfo:
    def shape(space: Any) -> list[int]:
        # gym (SB3 1.x) wrote "shape", gymnasium writes "_shape".
        return list(space["shape"] if "shape" in space else space["_shape"])

    try:
        obs_shape = shape(data["observation_space"])
        act_shape = shape(data["action_space"])
        space_type = str(data["observation_space"].get(":type:", ""))
    except (KeyError, TypeError, AttributeError):
        raise AgentError(f"{path} has no Box observation/action spaces") from None
    flat = len(obs_shape) == 1 and len(act_shape) == 1
    if not flat or not all(type(n) is int and 0 < n <= _MAX_SPACE_SIZE for n in obs_shape + act_shape):
        shown = str(obs_shape)[:40], str(act_shape)[:40]
        raise AgentError(f"{path}: expected flat Box spaces, got {shown[0]} and {shown[1]}")
    legacy = version.startswith(("0.", "1.")) or "'gym." in space_type
    steps = data.get("num_timesteps")
    return ModelInfo(
        version, int(obs_shape[0]), int(act_shape[0]), legacy, steps if type(steps) is int else None
    )


def inspect_model(path: str | os.PathLike) -> ModelInfo:
    """Reads a SB3 zip's metadata; AgentError when it is not one."""
    return read_zip(Path(path)).info


def safe_custom_objects(path: str | os.PathLike, known: Mapping[str, Any]) -> dict[str, Any]:
    """``custom_objects`` for SB3's ``PPO.load(path)`` that replace every pickled entry of the zip's
    ``data`` (so SB3 unpickles none of them): by ``known``'s value where it has one, else by None
    (what SB3 rebuilds when it starts learning: the last observation, the episode buffers)."""
    data = read_zip(Path(path)).data
    pickled = [key for key, value in data.items() if isinstance(value, Mapping) and ":serialized:" in value]
    return {key: known.get(key) for key in pickled}


# The activations SB3 policies are built with, by the name `data` records for policy_kwargs'


def recorded_env_files(model: str | os.PathLike) -> Any:
    """The robot and world files an SB3 zip records (``snakesim_env_files``), or None; read as plain
    JSON, nothing unpickled. AgentError when the file is not an SB3 model."""
    return read_zip(Path(model)).data.get(RECORDED_FILES_KEY)
