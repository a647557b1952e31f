"""Errors of the user's input, reported by every subcommand as one line (no traceback)."""

from __future__ import annotations

import os
from pathlib import Path


class UserError(Exception):
    """An error of the user's input: reported as one line, no traceback."""


def one_line(message: object) -> str:
    return " ".join(str(message).split())


def check_writable(path: str | os.PathLike, what: str = "") -> Path:
    """The output path, if its directory exists and is writable; UserError otherwise."""
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    label = f"{what} {path}" if what else str(path)
    if path.is_dir():
        raise UserError(f"cannot write {label}: it is a directory")
    if not parent.is_dir():
        raise UserError(f"cannot write {label}: directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise UserError(f"cannot write {label}: directory {parent} is not writable")
    return path
