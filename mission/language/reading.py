"""Read a document file under bounds: a regular file only, at most `MAX_FILE_BYTES`, UTF-8 text.

The file is checked with `stat` before it is opened (a FIFO, a device, a folder or a kernel pseudo-file is refused,
so that nothing blocks or reads for ever) and again with `fstat` once open (it may have been swapped between the
two). Reading stops one byte past the cap whatever `stat` said, since pseudo-files report a size of 0.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from mission.errors import AuvError
from mission.language.limits import MAX_FILE_BYTES, PSEUDO_FILE_ROOTS


class UnreadableFile(AuvError):
    """A document file that cannot or may not be read; the message names the path only, never its content."""


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _under_pseudo_root(path: Path) -> str | None:
    try:
        resolved = path.resolve()
    except (OSError, RuntimeError):  # a symlink loop: stat reports it below
        return None
    for root in PSEUDO_FILE_ROOTS:
        if resolved == Path(root) or resolved.is_relative_to(root):
            return root
    return None


def _oserror(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def check_readable(path: Path) -> None:
    """Raise UnreadableFile unless `path` names a regular file of at most `MAX_FILE_BYTES` (nothing is opened)."""
    root = _under_pseudo_root(path)
    if root is not None:
        raise UnreadableFile(f"{path} is a system file under {root}, not a document")
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise UnreadableFile(f"{path} does not exist") from None
    except OSError as exc:
        raise UnreadableFile(f"cannot read {path}: {_oserror(exc)}") from None
    if not stat.S_ISREG(info.st_mode):
        raise UnreadableFile(f"{path} is {_kind(info.st_mode)}, not a regular file")
    if info.st_size > MAX_FILE_BYTES:
        raise UnreadableFile(f"{path} is {info.st_size / 1e6:.1f} MB; files over {MAX_FILE_BYTES // 2**20} MB "
                             "are refused")


def read_bounded(path: Path) -> str:
    """The text of a document file, or UnreadableFile saying why not (with the path, never the content)."""
    check_readable(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise UnreadableFile(f"cannot read {path}: {_oserror(exc)}") from None
    try:
        with os.fdopen(fd, "rb") as handle:
            mode = os.fstat(handle.fileno()).st_mode
            if not stat.S_ISREG(mode):
                raise UnreadableFile(f"{path} is {_kind(mode)}, not a regular file")
            data = handle.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise UnreadableFile(f"cannot read {path}: {_oserror(exc)}") from None
    if len(data) > MAX_FILE_BYTES:
        raise UnreadableFile(f"{path} is over {MAX_FILE_BYTES // 2**20} MB; larger files are refused")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise UnreadableFile(f"{path} is not UTF-8 text (undecodable byte at offset {exc.start})") from None
