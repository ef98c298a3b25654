"""File I/O (User Manual ch. 15, L2693-3030): File, StreamReader, StreamWriter,
confined to the run's sandbox folder.

Devices: ``/flash``, ``/ROMDISK`` and ``/flash2``-``/flash8`` are folders of the
same name inside the sandbox (rt.sandbox); ``/NVRAM/file1``-``file16`` are
record files kept by the twin with the manual's size rules (L2927-3030): a file
gets a fixed size at creation (``-size n``, 4 to 7872 bytes, default 1024),
costs 1 byte plus 1 byte per record, each Write/WriteLine is one record of at
most 255 bytes; a full file raises -323 "Device full", unless created with
``-wrap``, which drops the oldest whole records.  Serial devices (``/dev/com1``
...) need hardware: opening one raises -3103.  Paths are case-sensitive; a name
may not start with "." (L2710), so a path cannot leave the sandbox; a symbolic link,
a device or a FIFO inside it is refused like a bad path, -3111
(twin.controller.sandbox, docs/robustness.md).
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field
from pathlib import Path

from ....controller.sandbox import Sandbox, SandboxError
from . import codes
from ..values import GplArray, format_value
from . import gpl_class, shared
from .members import stored
from .state import robot_state

FOLDER_DEVICES = ("flash", "ROMDISK", "flash2", "flash3", "flash4", "flash5", "flash6", "flash7", "flash8")
NVRAM_FILES = {f"file{i}" for i in range(1, 17)}
NVRAM_DEFAULT_SIZE, NVRAM_MIN_SIZE, NVRAM_MAX_SIZE = 1024, 4, 7872
NVRAM_MAX_RECORD = 255
MAX_NAME = 43


@dataclass
class NvramFile:
    size: int
    wrap: bool
    records: list[bytes] = field(default_factory=list)

    def used(self) -> int:
        return 1 + sum(len(r) + 1 for r in self.records)

    def append(self, record: bytes) -> None:
        if len(record) > NVRAM_MAX_RECORD:
            raise codes.fail(codes.INVALID_ARGUMENT, f"NVRAM record of {len(record)} bytes (255 at most)")
        if 1 + len(record) + 1 > self.size:
            raise codes.fail(codes.DEVICE_FULL)
        if self.used() + len(record) + 1 > self.size:
            if not self.wrap:
                raise codes.fail(codes.DEVICE_FULL)
            while self.used() + len(record) + 1 > self.size:
                self.records.pop(0)
        self.records.append(record)

    def content(self) -> bytes:
        return b"".join(self.records)


def _split_switches(path: str) -> tuple[str, dict]:
    """'/NVRAM/file2 -size 64 -wrap' -> ('/NVRAM/file2', {'size': 64, 'wrap': True})."""
    words = str(path).split()
    if not words:
        raise codes.fail(codes.INVALID_PATH, "empty path")
    switches: dict = {}
    i = 1
    while i < len(words):
        word = words[i].lower()
        if word == "-wrap":
            switches["wrap"] = True
        elif word == "-size" and i + 1 < len(words):
            i += 1
            switches["size"] = int(words[i])
        else:
            raise codes.fail(codes.INVALID_PATH, f"{path} (unknown switch {words[i]})")
        i += 1
    return words[0], switches


def _parts(path: str) -> list[str]:
    if not path.startswith("/"):
        raise codes.fail(codes.INVALID_PATH, f"{path} (paths start with a device, e.g. /flash)")
    parts = [p for p in path.split("/") if p]
    for name in parts:
        if name.startswith(".") or len(name) > MAX_NAME or not name.isprintable() or not name.isascii():
            raise codes.fail(codes.INVALID_PATH, path)
    return parts


def sandbox_path(rt, path: str) -> Path:
    """The sandbox file or folder behind a GPL path on a folder device."""
    parts = _parts(path)
    if not parts or parts[0] not in FOLDER_DEVICES:
        if parts and parts[0] == "dev":
            raise codes.fail(codes.NOT_SUPPORTED, f"{path} (serial ports need hardware)")
        raise codes.fail(codes.INVALID_PATH, f"{path} (devices: /flash, /ROMDISK, /flash2-8, /NVRAM)")
    box = Sandbox(rt.sandbox)
    _sandboxed(box.make_folders, box.root / parts[0])  # the controller's devices always exist
    return _sandboxed(box.path, *parts)


def _sandboxed(operation, *args):
    """A sandbox operation; a path it refuses is the program's -3111 Invalid file path."""
    try:
        return operation(*args)
    except SandboxError as err:
        raise codes.fail(codes.INVALID_PATH, f"{err.path} {err.reason}") from None


def _nvram_name(path: str) -> str | None:
    parts = _parts(path)
    if not parts or parts[0] != "NVRAM":
        return None
    if len(parts) != 2 or parts[1] not in NVRAM_FILES:
        raise codes.fail(codes.INVALID_PATH, f"{path} (NVRAM files are /NVRAM/file1 to file16)")
    return parts[1]


def _nvram(rt, name: str, switches: dict | None = None, create: bool = False) -> NvramFile:
    files = robot_state(rt).nvram
    if name not in files:
        if not create:
            raise codes.fail(codes.FILE_NOT_FOUND, f"/NVRAM/{name}")
        size = int((switches or {}).get("size", NVRAM_DEFAULT_SIZE))
        if not NVRAM_MIN_SIZE <= size <= NVRAM_MAX_SIZE:
            raise codes.fail(codes.INVALID_ARGUMENT, f"NVRAM -size {size} ({NVRAM_MIN_SIZE} to {NVRAM_MAX_SIZE})")
        files[name] = NvramFile(size, bool((switches or {}).get("wrap", False)))
    return files[name]


def read_bytes(rt, path: str) -> bytes:
    """The bytes of a file on any device (switches after the path are ignored)."""
    path, _ = _split_switches(path)
    name = _nvram_name(path)
    if name is not None:
        return _nvram(rt, name).content()
    real = sandbox_path(rt, path)
    if not real.is_file():
        raise codes.fail(codes.FILE_NOT_FOUND, path)
    return _sandboxed(Sandbox(rt.sandbox).read_bytes, real)


@gpl_class("StreamReader")
class StreamReader:
    """Reads a file byte by byte or line by line (Table 15-3)."""

    def __init__(self, rt, path):
        self._data = read_bytes(rt, str(path))
        self._pos = 0
        self._open = True

    def _check(self) -> None:
        if not self._open:
            raise codes.fail(codes.FILE_CLOSED)

    def Close(self) -> None:
        self._open = False

    def Peek(self) -> int:
        """The next byte without consuming it; -1 at the end."""
        self._check()
        return self._data[self._pos] if self._pos < len(self._data) else -1

    def Read(self) -> int:
        """The next byte; -1 at the end."""
        value = self.Peek()
        if value >= 0:
            self._pos += 1
        return value

    def ReadLine(self) -> str:
        """The next line without its terminator (LF, CR or CR-LF); "" at the end."""
        self._check()
        data, start = self._data, self._pos
        end = start
        while end < len(data) and data[end] not in (10, 13):
            end += 1
        line = data[start:end].decode("latin-1")
        if end < len(data) and data[end] == 13 and end + 1 < len(data) and data[end + 1] == 10:
            end += 1
        self._pos = min(end + 1, len(data))
        return line


@gpl_class("StreamWriter")
class StreamWriter:
    """Writes a file (Table 15-4).  Without `append` an existing file is replaced."""

    def __init__(self, rt, path, append=False):
        path, switches = _split_switches(str(path))
        self._path = path
        self._open = True
        self._pending: list[str] = []
        self._newline = "\r\n"
        name = _nvram_name(path)
        if name is not None:
            files = robot_state(rt).nvram
            if not append:
                files.pop(name, None)
            self._nvram = _nvram(rt, name, switches, create=True)
            self._file = None
            self._autoflush = True
        else:
            self._nvram = None
            real = sandbox_path(rt, path)
            if not real.parent.is_dir():
                raise codes.fail(codes.FILE_NOT_FOUND, f"{path} (no such folder)")
            self._file = _sandboxed(Sandbox(rt.sandbox).open, real, "ab" if append else "wb")
            self._autoflush = False

    AutoFlush = stored("_autoflush", bool)
    NewLine = stored("_newline", str)

    def _check(self) -> None:
        if not self._open:
            raise codes.fail(codes.FILE_CLOSED, self._path)

    def Write(self, value) -> None:
        self._check()
        self._emit(format_value(value))

    def WriteLine(self, value="") -> None:
        self._check()
        self._emit(format_value(value) + self._newline)

    def _emit(self, text: str) -> None:
        if self._nvram is not None:
            self._nvram.append(text.encode("latin-1"))
            return
        self._pending.append(text)
        if self._autoflush:
            self.Flush()

    def Flush(self) -> None:
        self._check()
        if self._file is not None:
            self._file.write("".join(self._pending).encode("latin-1"))
            self._file.flush()
        self._pending.clear()

    def Close(self) -> None:
        if self._open:
            self.Flush()
            if self._file is not None:
                self._file.close()
            self._open = False


@gpl_class("File")
class File:
    """The global File class (Table 15-2)."""

    @shared
    def ComputeCRC(rt, path) -> int:
        """CRC-32 (zlib's polynomial; the manual does not name one) of the file's bytes."""
        return zlib.crc32(read_bytes(rt, str(path)))

    @shared
    def ComputeLength(rt, path) -> int:
        return len(read_bytes(rt, str(path)))

    Length = ComputeLength

    @shared
    def Copy(rt, source, destination, overwrite=False) -> None:
        data = read_bytes(rt, str(source))
        target = sandbox_path(rt, str(destination))
        if target.exists() and not overwrite:
            raise codes.fail(codes.INVALID_PATH, f"{destination} exists")
        _sandboxed(Sandbox(rt.sandbox).write_bytes, target, data)

    @shared
    def CreateDirectory(rt, path) -> None:
        _sandboxed(Sandbox(rt.sandbox).make_folders, sandbox_path(rt, str(path)))

    @shared
    def DeleteDirectory(rt, path) -> None:
        real = sandbox_path(rt, str(path))
        if not real.is_dir():
            raise codes.fail(codes.FILE_NOT_FOUND, str(path))
        if any(real.iterdir()):
            raise codes.fail(codes.INVALID_PATH, f"{path} is not empty")
        real.rmdir()

    @shared
    def DeleteFile(rt, path) -> None:
        name = _nvram_name(str(path))
        if name is not None:
            if robot_state(rt).nvram.pop(name, None) is None:
                raise codes.fail(codes.FILE_NOT_FOUND, str(path))
            return
        real = sandbox_path(rt, str(path))
        if not real.is_file():
            raise codes.fail(codes.FILE_NOT_FOUND, str(path))
        real.unlink()

    @shared
    def GetDirectories(rt, path) -> GplArray:
        return _listing(rt, str(path), folders=True)

    @shared
    def GetFiles(rt, path) -> GplArray:
        if str(path).strip("/") == "NVRAM":
            return GplArray.of(sorted(robot_state(rt).nvram), "")
        return _listing(rt, str(path), folders=False)


def _listing(rt, path: str, folders: bool) -> GplArray:
    real = sandbox_path(rt, path)
    if not real.is_dir():
        raise codes.fail(codes.FILE_NOT_FOUND, path)
    entries = _sandboxed(Sandbox(rt.sandbox).entries, real)
    return GplArray.of([p.name for p in entries if p.is_dir() == folders], "")
