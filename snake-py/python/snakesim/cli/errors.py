"""Errors of the user's input, reported by every subcommand as one line (no traceback), and the checks
of output paths every subcommand makes before it writes."""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from snakesim import _core
from snakesim.files import is_input, output_kind


class UserError(Exception):
    """An error of the user's input: reported as one line, no traceback."""


def one_line(message: object) -> str:
    return " ".join(str(message).split())


def capped(line: str) -> str:
    """``line`` cut in its middle to LIMITS['error_chars'] characters, by the Rust side's own rule:
    the start names the command and the file, the end says what was expected."""
    return _core.capped_message(line)


def report(command: str, message: object) -> str:
    """The one line a failed ``snakesim COMMAND`` prints on stderr."""
    return capped(f"snakesim {command}: error: {one_line(message)}")


def _same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    try:
        return os.path.samefile(a, b)  # also through symlinks and hard links
    except OSError:  # one of them does not exist (yet)
        return False


def check_writable(path: str | os.PathLike, what: str = "", inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """The output path, if the command can write it; UserError otherwise: its directory is missing or
    not writable, it is a directory, a socket or a block device, or it is a file the command reads:
    one of ``inputs`` (named, perhaps not read yet) or one it has read already
    (:func:`snakesim.files.is_input`: the robot file and its URDF, the world and its heightfield, a
    model and its statistics, however the path is spelled). A character device (/dev/null) or a FIFO is
    written through (snakesim.files.output_file), so it only has to be writable itself."""
    path = Path(path)
    label = f"{what} {path}" if what else str(path)
    real = Path(os.path.realpath(path))  # a symlink's target is what gets written
    kind = output_kind(real)
    if kind == "directory":
        raise UserError(f"cannot write {label}: it is a directory")
    if kind == "other":
        raise UserError(f"cannot write {label}: it is a socket or a block device, not a file")
    if kind in ("device", "fifo"):
        if not os.access(real, os.W_OK):
            raise UserError(f"cannot write {label}: it is not writable")
        return path
    parent = real.parent
    if not parent.is_dir():
        raise UserError(f"cannot write {label}: directory {path.parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise UserError(f"cannot write {label}: directory {path.parent} is not writable")
    for source in inputs:
        if _same_file(real, source):
            raise UserError(f"cannot write {label}: it is {os.fspath(source)}, which this command reads")
    if is_input(real):
        # Read already (a robot's URDF, a world's heightfield, a model's files), whatever path named it.
        raise UserError(f"cannot write {label}: it is {os.fspath(path)}, which this command reads")
    return path


def check_distinct(outputs: Sequence[tuple[str | os.PathLike, str]]) -> None:
    """UserError when two of a command's outputs (path, flag) name the same file (a device such as
    /dev/null may take several)."""
    files = [(path, what) for path, what in outputs if output_kind(path) != "device"]
    for i, (path, what) in enumerate(files):
        for other, other_what in files[:i]:
            real, other_real = os.path.realpath(path), os.path.realpath(other)
            if real == other_real or _same_file(path, other):
                raise UserError(
                    f"{other_what} {os.fspath(other)} and {what} {os.fspath(path)} name the same file; "
                    "give each its own path"
                )


def env_files(env_kwargs: Mapping[str, Any]) -> list[str]:
    """The files an env's keywords name (a robot file, a world file), which a command reads."""
    return [value for key in ("robot", "world") if isinstance(value := env_kwargs.get(key), str)]
