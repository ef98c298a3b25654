"""The folder a program's file I/O is confined to, shared by V+ (ATTACH "DISK", FOPEN*,
FDELETE, directory listings) and GPL (File, StreamReader/Writer, /flash...).

The languages map their own file names to a list of path components; this module turns
them into a host path and refuses (SandboxError, which each language reports with its own
error code) anything that could lead outside the root:

* a component that is empty, ".", "..", or holds a separator or a NUL byte;
* an existing component that is a symbolic link (resolve-and-check of every component,
  and O_NOFOLLOW when a file is opened, so a link planted inside the folder leads
  nowhere) or that is neither a regular file nor a folder (a FIFO would hang a read, a
  device would be written);
* a root that is itself a symbolic link or not a folder: `<program>-files` beside the
  report is a predictable name, and a link planted there would redirect every write.

Listings leave out the entries that could not be opened (links, devices, FIFOs).  The
program cannot make links, so nothing changes between the check and the use.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path


class SandboxError(Exception):
    """A path the sandbox refuses; `reason` says why in a few words."""

    def __init__(self, path: str | Path, reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path = str(path)
        self.reason = reason


def check_root(root: str | Path) -> None:
    """Refuse a sandbox root that exists as a symbolic link or as anything but a folder."""
    try:
        mode = os.lstat(root).st_mode
    except FileNotFoundError:
        return
    if stat.S_ISLNK(mode):
        raise SandboxError(root, "is a symbolic link (the sandbox folder must be a real folder)")
    if not stat.S_ISDIR(mode):
        raise SandboxError(root, "exists and is not a folder")


class Sandbox:
    """Paths inside `root`, checked component by component."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(os.path.abspath(root))

    def path(self, *parts: str) -> Path:
        """The host path of `parts` inside the root (which need not exist yet)."""
        check_root(self.root)
        for part in parts:
            if part in ("", ".", "..") or "/" in part or "\\" in part or "\0" in part:
                raise SandboxError(repr(part), "is not a file or folder name")
        current = self.root
        for part in parts:
            current = current / part
            try:
                mode = os.lstat(current).st_mode
            except (FileNotFoundError, NotADirectoryError):
                return self.root.joinpath(*parts)  # the rest does not exist: nothing to follow
            if stat.S_ISLNK(mode):
                raise SandboxError(self.relative(current), "is a symbolic link")
            if not (stat.S_ISDIR(mode) or stat.S_ISREG(mode)):
                raise SandboxError(self.relative(current), "is not a regular file or folder")
        return current

    def inside(self, path: Path) -> Path:
        """Check a host path already built under the root (every component, as `path`)."""
        try:
            relative = Path(os.path.abspath(path)).relative_to(self.root)
        except ValueError:
            raise SandboxError(path, "is outside the sandbox") from None
        return self.path(*relative.parts)

    def relative(self, path: Path) -> str:
        try:
            return str(Path(path).relative_to(self.root))
        except ValueError:
            return str(path)

    def make_folders(self, folder: Path) -> None:
        """mkdir -p inside the sandbox, root included, after checking each component."""
        folder = self.inside(folder)
        self.root.mkdir(parents=True, exist_ok=True)
        check_root(self.root)
        folder.mkdir(parents=True, exist_ok=True)
        self.inside(folder)

    def open(self, path: Path, mode: str):
        """open(path, mode) for 'rb', 'wb', 'ab', 'xb' or 'r+b' without following a final link."""
        path = self.inside(path)
        flags = {"rb": os.O_RDONLY, "wb": os.O_WRONLY | os.O_CREAT | os.O_TRUNC,
                 "ab": os.O_WRONLY | os.O_CREAT | os.O_APPEND, "xb": os.O_WRONLY | os.O_CREAT | os.O_EXCL,
                 "r+b": os.O_RDWR}[mode]
        fd = os.open(path, flags | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0), 0o666)
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise SandboxError(self.relative(path), "is not a regular file")
        return os.fdopen(fd, mode)

    def read_bytes(self, path: Path) -> bytes:
        with self.open(path, "rb") as f:
            return f.read()

    def write_bytes(self, path: Path, data: bytes, mode: str = "wb") -> None:
        with self.open(path, mode) as f:
            f.write(data)

    def entries(self, folder: Path) -> list[Path]:
        """The regular files and folders in `folder`, sorted by name (links and devices left out)."""
        folder = self.inside(folder)
        found = []
        with os.scandir(folder) as scan:
            for entry in scan:
                if entry.is_symlink():
                    continue
                if entry.is_dir(follow_symlinks=False) or entry.is_file(follow_symlinks=False):
                    found.append(Path(entry.path))
        return sorted(found, key=lambda p: p.name)
