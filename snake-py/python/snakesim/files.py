"""Writing output files whole or not at all: a failed or interrupted write never truncates or replaces
an existing file."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

T = TypeVar("T")


def write_atomically(target: str | os.PathLike, write: Callable[[str], T]) -> T:
    """Calls ``write(tmp)`` for a temporary file beside ``target`` whose name ends like the target's
    (writers that choose the format by the name choose the right one), then renames it over
    ``target``; returns what ``write`` returned. On any error the temporary file is removed and
    ``target`` is left as it was."""
    target = Path(target)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=target.suffix)
    os.close(fd)
    try:
        # mkstemp makes the file private (0600); give the result the permissions a new file gets.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        result = write(tmp)
        os.replace(tmp, target)
        return result
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
