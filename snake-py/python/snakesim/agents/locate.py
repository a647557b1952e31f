"""What a path holds, found out once: a native model, an SB3 zip (with the statistics beside it) or a
run directory (its config.yaml and its final model, else its latest checkpoint). Judged by content,
not name; nothing here reads a model's tensors."""

from __future__ import annotations

import dataclasses
import os
import re
import stat
from pathlib import Path
from typing import Any

from snakesim.agents.native import NativeAgent
from snakesim.agents.protocol import Agent, AgentError
from snakesim.agents.sb3 import SB3Agent
from snakesim.files import FileError, open_regular
from snakesim.runs import config as runconfig
from snakesim.runs.rundir import (
    CONFIG_FILE,
    EXPORTED_STATISTICS_SUFFIX,
    MODEL_FILE,
    NATIVE_MODEL_FILE,
    VECNORMALIZE_FILE,
    checkpoint_paths,
    checkpoints,
)


def _sniff(path: Path) -> str | None:
    """``"safetensors"``, ``"zip"`` or None, by the first bytes of a regular file; OSError and
    FileError pass through."""
    with open_regular(path, "model_bytes") as f:
        head = f.read(9)
    if head[:4] == b"PK\x03\x04":
        return "zip"
    if len(head) == 9 and head[8:9] == b"{" and 0 < int.from_bytes(head[:8], "little") < 1 << 32:
        return "safetensors"
    return None


def model_format(path: str | os.PathLike) -> str | None:
    """What a model file holds, judged by its first bytes rather than its name: ``"safetensors"`` (a
    snakesim model: an 8-byte header length, then the JSON header), ``"zip"`` (a Stable-Baselines3
    model), or None (neither, or unreadable)."""
    try:
        return _sniff(Path(path))
    except (OSError, FileError):
        return None


def normalizer_beside(zip_path: str | os.PathLike) -> Path | None:
    """The VecNormalize statistics that belong to an SB3 zip, when they are there: ``NAME_vecnormalize.pkl``
    beside ``NAME.zip`` (what ``snakesim export`` writes), or a run directory's own (``vecnormalize.pkl``
    beside ``model.zip``, ``vecnormalize_<T>_steps.pkl`` beside ``model_<T>_steps.zip``)."""
    path = Path(zip_path)
    candidates = [path.with_name(path.stem + EXPORTED_STATISTICS_SUFFIX)]
    if path.name == MODEL_FILE:
        candidates.append(path.with_name(VECNORMALIZE_FILE))
    match = re.fullmatch(r"model_(\d+)_steps\.zip", path.name)
    if match:
        candidates.append(path.with_name(f"vecnormalize_{match.group(1)}_steps.pkl"))
    return next((c for c in candidates if c.is_file()), None)


@dataclasses.dataclass(frozen=True)
class Located:
    """What the loader was given, found out once: the class of agent that reads it, and its files."""

    reader: type[Agent]  # NativeAgent or SB3Agent: its read(located, ...) reads the files
    model: Path
    config: dict[str, Any] | None = None  # a run directory's config.yaml
    normalizer: Path | None = None  # an SB3 model's VecNormalize statistics
    run: Path | None = None  # the run directory

    @property
    def files(self) -> tuple[str, ...]:
        """Every file the agent is read from."""
        config = None if self.run is None else self.run / CONFIG_FILE
        return tuple(os.fspath(f) for f in (self.model, config, self.normalizer) if f is not None)


def locate(source: Path) -> Located:
    """What ``source`` holds (a model file or a run directory); AgentError when it is neither."""
    try:
        mode = os.stat(source).st_mode
    except FileNotFoundError:
        raise AgentError(f"{source} does not exist (expected a run directory or a model .zip)") from None
    except OSError as error:
        raise AgentError(f"cannot read {source}: {error.strerror or error}") from None
    if stat.S_ISDIR(mode):
        return _locate_in_run(source)
    if not stat.S_ISREG(mode):
        raise AgentError(f"{source}: not a regular file (a device, FIFO or socket)")
    try:
        held = _sniff(source)
    except FileError as error:
        raise AgentError(str(error)) from None
    except OSError as error:
        raise AgentError(f"cannot read {source}: {error.strerror or error}") from None
    # A file that is neither by content is judged by its name, for the reader's own error.
    held = held or {".zip": "zip", ".safetensors": "safetensors"}.get(source.suffix)
    if held == "safetensors":
        return Located(NativeAgent, source)
    if held == "zip":
        return Located(SB3Agent, source, normalizer=normalizer_beside(source))
    raise AgentError(
        f"{source} is neither a snakesim model (safetensors) nor a Stable-Baselines3 model (zip)"
    )


def _locate_in_run(run: Path) -> Located:
    """A run directory: its config.yaml, and its final model, else its latest checkpoint."""
    config_path = run / CONFIG_FILE
    if not config_path.is_file():
        raise AgentError(f"{run} is not a run directory (no {CONFIG_FILE})")
    try:
        config = runconfig.load(config_path)
    except runconfig.ConfigError as error:
        raise AgentError(str(error)) from None
    native = config["trainer"] == "native"
    model = run / (NATIVE_MODEL_FILE if native else MODEL_FILE)
    normalizer = run / VECNORMALIZE_FILE
    if not model.is_file():
        found = checkpoints(run, native=native)
        if not found:
            raise AgentError(f"{run} has no {model.name} and no checkpoints yet")
        steps, model = found[-1]
        normalizer = checkpoint_paths(run, steps)[1]
    if native:
        return Located(NativeAgent, model, config, run=run)
    return Located(SB3Agent, model, config, normalizer if normalizer.is_file() else None, run)
