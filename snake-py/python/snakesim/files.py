"""Reading a user's files within bounds, and writing output files whole or not at all.

Reading: :func:`read_bytes` and :func:`open_regular` take regular files only (a FIFO, a socket or
``/dev/zero`` is refused at once, never waited on or read forever) of at most a size cap from
``LIMITS``; each file read joins the one set of the files this process reads (:func:`is_input`, shared
with the Rust core's readers). Writing: :func:`write_atomically` never truncates or replaces an existing
file half-way, never replaces a file the process read (:func:`rewrite_atomically` for a run's own
state), writes through a character device or a FIFO named as the output, and replaces the file a
symlink points to rather than the link.
"""

from __future__ import annotations

import errno
import fcntl
import os
import shutil
import stat
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO, TypeVar

from snakesim import _core

# snakesim.limits's table, from _core: this module is a leaf (it imports no other snakesim module).
LIMITS = _core.LIMITS

T = TypeVar("T")


class FileError(ValueError):
    """A file that cannot be read or written as asked (not a regular file, too large, a FIFO nobody
    reads); the message names the file."""


def _size(size: int) -> str:
    return f"{size >> 20} MiB" if size and size % (1 << 20) == 0 else f"{size:,} bytes"


def check_size(size: int, limit: str, what: str) -> None:
    """FileError when ``size`` bytes exceed ``LIMITS[limit]`` (``what`` names the file or member)."""
    cap = LIMITS[limit]
    if size > cap:
        raise FileError(f"{what} is {_size(size)}, more than the {_size(cap)} allowed (LIMITS['{limit}'])")


def open_regular(path: str | os.PathLike, limit: str) -> BinaryIO:
    """``path`` opened for reading in binary, if it is a regular file of at most ``LIMITS[limit]``
    bytes; FileError otherwise (IsADirectoryError for a directory, the OSError of a missing or
    unreadable file)."""
    name = os.fspath(path)
    not_regular = f"{name}: not a regular file (a device, FIFO or socket)"
    try:
        # O_NONBLOCK: opening a FIFO for reading would wait for a writer; this way we get to refuse it.
        fd = os.open(name, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as error:
        if error.errno == errno.ENXIO:  # a socket (or a device without its driver)
            raise FileError(not_regular) from None
        raise
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), name)
        if not stat.S_ISREG(info.st_mode):
            raise FileError(not_regular)
        check_size(info.st_size, limit, name)
        # One set of the files this process reads, Rust's readers' and ours: no output replaces one.
        _core.remember_input(name)
        fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bytes(path: str | os.PathLike, limit: str) -> bytes:
    """The bytes of a regular file of at most ``LIMITS[limit]`` bytes (see :func:`open_regular`); a
    file that grows while read is cut off at the cap and refused."""
    with open_regular(path, limit) as f:
        data = f.read(LIMITS[limit] + 1)
    check_size(len(data), limit, os.fspath(path))
    return data


def read_text(path: str | os.PathLike, limit: str) -> str:
    """:func:`read_bytes` decoded as UTF-8 (UnicodeDecodeError if it is not)."""
    return read_bytes(path, limit).decode("utf-8")


def output_kind(path: str | os.PathLike) -> str | None:
    """What an output path names now: None (nothing), ``"file"``, ``"directory"``, ``"device"`` (a
    character device such as /dev/null), ``"fifo"``, or ``"other"`` (a socket, a block device);
    symlinks followed."""
    try:
        mode = os.stat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):  # nothing there (yet)
        return None
    if stat.S_ISREG(mode):
        return "file"
    if stat.S_ISDIR(mode):
        return "directory"
    if stat.S_ISCHR(mode):
        return "device"
    if stat.S_ISFIFO(mode):
        return "fifo"
    return "other"


def is_input(path: str | os.PathLike) -> bool:
    """True when ``path`` (after links, however it is spelled) is a file this process has read: a
    model, statistics or configuration read here, or a robot, URDF, world, heightfield or targets
    file read by the Rust core (one set for both, ``snake_core::files``)."""
    return _core.is_input(os.fspath(path))


def forget_input(path: str | os.PathLike) -> None:
    """Forgets that ``path`` was read: for a writer that replaces its own earlier output after
    reading it (a run's configuration on resume, a sweep's manifest)."""
    _core.forget_input(os.fspath(path))


class InputOverwrite(FileError):
    """An output that would replace a file the process reads."""


def write_atomically(target: str | os.PathLike, write: Callable[[str], T]) -> T:
    """Calls ``write(tmp)`` for a temporary file whose name ends like the target's (writers that
    choose the format by the name choose the right one), then puts it in place (see
    :func:`output_file`); returns what ``write`` returned."""
    with output_file(target) as tmp:
        return write(tmp)


def rewrite_atomically(target: str | os.PathLike, write: Callable[[str], T]) -> T:
    """:func:`write_atomically` for a writer that replaces its own state after reading it (a run's
    configuration, versions and evaluations on resume, a sweep's manifest, a trainer's checkpoints):
    the one kind of output that may replace a file the process read."""
    forget_input(target)
    return write_atomically(target, write)


@contextmanager
def output_file(target: str | os.PathLike) -> Iterator[str]:
    """The name of a temporary file to write ``target``'s content to, put in place when the block
    ends without error.

    A regular file (or none) is replaced by renaming the temporary file beside it over it: on any
    error the temporary file is removed and the target is left as it was. A symlink's target is
    replaced and the link kept. A character device (``/dev/null``) or a FIFO is written through, never
    replaced by a file; a FIFO that nobody reads is refused rather than waited on. Anything else (a
    directory, a socket) is FileError.
    """
    shown = os.fspath(target)
    target = Path(os.path.realpath(target))
    kind = output_kind(target)
    if kind in ("device", "fifo"):
        with _written_through(target, shown) as tmp:
            yield tmp
        return
    if kind not in (None, "file"):
        raise FileError(f"cannot write {shown}: it is a {'directory' if kind == 'directory' else 'socket'}")
    if kind == "file" and is_input(target):
        raise InputOverwrite(f"cannot write {shown}: it is a file this run reads")
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=target.suffix)
    os.close(fd)
    try:
        # mkstemp makes the file private (0600); give the result the permissions a new file gets.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        yield tmp
        if is_input(target):  # read while the output was written
            raise InputOverwrite(f"cannot write {shown}: it is a file this run reads")
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


@contextmanager
def _written_through(target: Path, shown: str) -> Iterator[str]:
    """A private temporary file (a writer may need a name to choose its format by) whose bytes are
    copied into the device or FIFO ``target`` at the end."""
    try:
        # O_NONBLOCK: opening a FIFO that nobody reads fails with ENXIO instead of waiting for ever.
        fd = os.open(target, os.O_WRONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as error:
        if error.errno == errno.ENXIO:
            raise FileError(f"cannot write {shown}: a FIFO that nobody reads") from None
        raise
    # Unbuffered: a reader that goes away fails the copy below, not a flush at close.
    scratch = tempfile.TemporaryDirectory(prefix="snakesim-out-")
    with os.fdopen(fd, "wb", buffering=0) as out, scratch as tmpdir:
        fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
        tmp = os.path.join(tmpdir, f"out{target.suffix}")
        yield tmp
        try:
            with open(tmp, "rb") as f:
                shutil.copyfileobj(f, out)
        except BrokenPipeError:
            raise FileError(f"cannot write {shown}: its reader went away") from None
