"""Output files (report, recording, JUnit) written so that nothing is lost or clobbered.

An output is written to a temporary file in its folder and renamed over the target at
the end, so a reader never sees half of it; the rename happens only over a regular file
(or where there is nothing yet): `os.replace` over a device node, a FIFO or a folder
would replace it (as root, `--report /dev/full` used to turn the device into a file).
"""

from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path


class OutputError(OSError):
    """The output path names something that is not a regular file."""


def check_replaceable(path: str | os.PathLike) -> None:
    """Raise OutputError unless `path` is absent or a regular file (links followed)."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return
    if not stat.S_ISREG(mode):
        kind = "a folder" if stat.S_ISDIR(mode) else "a device, FIFO or socket"
        raise OutputError(f"{path} is {kind}, not a regular file: refusing to replace it")


def temporary_beside(path: str | os.PathLike) -> Path:
    """A fresh temporary file in the target's folder (so the final rename is atomic)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    # mkstemp makes the file 0600; a report or recording is an ordinary output that a CI
    # artifact step (often another user) must read, so give it the mode open() would.
    os.fchmod(fd, 0o666 & ~_umask())
    os.close(fd)
    return Path(tmp)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def replace_output(tmp: str | os.PathLike, path: str | os.PathLike) -> None:
    """Rename the finished temporary file over `path` (through a symbolic link, onto the
    file it names); the temporary file is removed if that is refused."""
    target = Path(os.path.realpath(path))
    try:
        check_replaceable(target)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_atomically(path: str | os.PathLike, text: str) -> None:
    """Write `text` (UTF-8) to `path` atomically, only over a regular file."""
    check_replaceable(path)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_beside(os.path.realpath(path))
    try:
        tmp.write_text(text, encoding="utf-8")
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    replace_output(tmp, path)
