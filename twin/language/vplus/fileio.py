"""V+ logical units and the devices behind them (V+ guide v17, "Input/Output
Control"; eV+ guide, same chapter).

* DISK: files in the run's sandbox folder (`VPlusSystem.sandbox`).  A file
  spec `unit:path\\name.ext` maps to `sandbox/UNIT/path/name.ext`, or
  `sandbox/path/name.ext` without a unit; names are case-insensitive as on
  the controller's DOS-style disks and may not leave the sandbox (no "..", no
  symbolic link, no device: twin.controller.sandbox; *Invalid file
  specification* otherwise).  Records are
  variable length (CR LF ends a record, Ctrl-Z ends the file) unless FOPEN_
  gave a record length.  WRITE goes straight to the file, so nothing is lost
  when a program ends without FCLOSE.
* SERIAL:n: an in-memory line a test or scene feeds (`SerialLine.feed`) and
  reads back (`SerialLine.sent`).
* TERMINAL (logical unit 4): the system console.
* TCP: a network server or client on loopback (tcp.py), opened with FOPEN.
* The pendant (unit 1), graphics windows (20-23), and any other device are
  absent, as on a controller without that hardware: ATTACH reports
  *Device not ready* through IOSTAT and the program goes on.

I/O errors never stop a program: each operation stores its status, which
IOSTAT(lun) returns (1 success, < 0 the error code), as the guides describe.
"""

from __future__ import annotations

import fnmatch
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from ...controller.sandbox import Sandbox, SandboxError
from ...controller.scheduler import NETWORK_CYCLE
from . import messages as msg
from .values import to_int

if TYPE_CHECKING:
    from .tcp import TcpEndpoint

TERMINAL_LUN = 4
DISK_LUNS = range(5, 15)  # handed out by ATTACH (lun, 4) "DISK"
SERIAL_LUNS = range(15, 20)
GRAPHICS_LUNS = range(20, 24)  # V+ guide v17, "Graphics Programming"
MAX_OPEN_FILES = 60  # V+ guide v17, "Disk I/O": the 61st open gives *Device not ready*
CTRL_Z = 26
RECORD_MAX = 512  # bytes in a variable-length record
RANDOM_ACCESS = 1  # FOPEN_ mode bit (V+ guide v17, "Random-Access Files")
RETURN_LUN = 4  # ATTACH mode bit: allocate a free unit and return its number


class IoError(Exception):
    """An I/O failure: stored as the unit's IOSTAT, never stops the program."""

    def __init__(self, code: int):
        super().__init__(msg.message(code))
        self.code = code


@dataclass
class SerialLine:
    """A serial port: bytes the program will read, bytes it has written."""

    number: int
    received: bytearray = field(default_factory=bytearray)
    sent: bytearray = field(default_factory=bytearray)
    owner: int | None = None  # task that has it attached
    # Called when bytes arrive: sets the attached task's event flag, so a
    # program in WAIT.EVENT wakes up ([000] "display()" serial example).
    listener: Callable[[], None] | None = None

    # Line errors a test or scene injects, each met by the next READ or GETC
    # ([000] "Serial I/O"): -522 parity or framing, -524 overrun, -504 BREAK.
    errors: list[int] = field(default_factory=list)

    def feed(self, data: bytes | str) -> None:
        self.received += data.encode("latin-1") if isinstance(data, str) else data
        self._wake()

    def fail(self, code: int) -> None:
        self.errors.append(code)
        self._wake()

    def _wake(self) -> None:
        if self.listener is not None:
            self.listener()

    def take_error(self) -> None:
        if self.errors:
            raise IoError(self.errors.pop(0))


@dataclass
class OpenFile:
    path: Path
    mode: str  # R, W, A or D (directory)
    record_length: int = 0
    random: bool = False
    data: bytes = b""  # what reads see (R and D)
    position: int = 0

    box: Sandbox | None = None

    def content(self) -> bytes:
        """What a READ sees: the file as opened, or as written so far (W and A:
        a file open for writing may be read too, [000] "Disk I/O")."""
        return self.data if self.mode in ("R", "D") else _sandboxed(self.box.read_bytes, self.path)


@dataclass
class Unit:
    """An attached logical unit."""

    device: str  # DISK, SERIAL:n, TERMINAL
    serial: SerialLine | None = None
    file: OpenFile | None = None
    tcp: TcpEndpoint | None = None


class Devices:
    """Every task's logical units, the disk sandbox and the serial lines."""

    def __init__(self, sandbox: Path | None, console, clock: Callable[[], float] = lambda: 0.0):
        self.sandbox = Path(sandbox) if sandbox is not None else None
        self.box = Sandbox(sandbox) if sandbox is not None else None
        self.console = console
        self.clock = clock  # simulated time: the network is polled once per instant
        self.serial_lines: dict[int, SerialLine] = {}
        self.units: dict[tuple[int, int], Unit] = {}
        self.status: dict[tuple[int, int], int] = {}
        self.last_length: dict[tuple[int, int], int] = {}
        self.typed = bytearray()  # terminal input GETC has not taken yet (RETURN is CR)

    # ------------------------------------------------------------ state
    def serial(self, number: int) -> SerialLine:
        return self.serial_lines.setdefault(number, SerialLine(number))

    def iostat(self, task: int, lun: int, select: int = 0) -> float:
        if select == 2:
            return float(self.last_length.get((task, lun), 0))
        if select in (1, 3):
            return 1.0  # prereads and no-wait writes complete at once here
        return float(self.status.get((task, lun), 0))

    def run(self, task: int, lun: int, operation, *args):
        """Do one I/O operation; its outcome becomes IOSTAT(lun)."""
        try:
            result = operation(task, lun, *args)
        except IoError as err:
            self.status[(task, lun)] = err.code
            return None
        self.status[(task, lun)] = 1
        return result

    def unit(self, task: int, lun: int) -> Unit:
        unit = self.units.get((task, lun))
        if unit is None:
            raise IoError(msg.NOT_ATTACHED)
        return unit

    def open_files(self) -> int:
        return sum(1 for u in self.units.values() if u.file is not None)

    # ------------------------------------------------------------ attach
    def free_lun(self, task: int, device: str) -> int:
        pool = DISK_LUNS if device in ("DISK", "TCP") else SERIAL_LUNS if device.startswith("SERIAL") else GRAPHICS_LUNS
        for lun in pool:
            if (task, lun) not in self.units:
                return lun
        raise IoError(msg.DEVICE_NOT_READY)

    def attach(self, task: int, lun: int, device: str) -> None:
        if (task, lun) in self.units:
            raise IoError(msg.ALREADY_ATTACHED)
        if device == "DISK":
            if self.sandbox is None:
                raise IoError(msg.DEVICE_NOT_READY)  # a run with no output folder has no disk
            self.units[(task, lun)] = Unit("DISK")
        elif device == "TERMINAL":
            self.units[(task, lun)] = Unit("TERMINAL")
        elif device == "TCP":
            from .tcp import TcpEndpoint

            self.units[(task, lun)] = Unit("TCP", tcp=TcpEndpoint(self.clock))
        elif (match := re.fullmatch(r"SERIAL:([1-9][0-9]?)", device)) is not None:
            line = self.serial(int(match[1]))
            if line.owner is not None and line.owner != task:
                raise IoError(msg.DEVICE_NOT_READY)  # only one task may hold a line
            line.owner = task
            self.units[(task, lun)] = Unit(device, serial=line)
        else:
            # The pendant, graphics windows and other hardware are absent.
            raise IoError(msg.DEVICE_NOT_READY)

    def detach(self, task: int, lun: int) -> None:
        unit = self.units.pop((task, lun), None)
        if unit is None:
            raise IoError(msg.NOT_ATTACHED)
        if unit.serial is not None:
            unit.serial.owner = None
            unit.serial.listener = None
        if unit.tcp is not None:
            unit.tcp.close()

    def release_task(self, task: int) -> None:
        """A program that ends normally has its units detached and files closed."""
        for key in [k for k in self.units if k[0] == task]:
            self.detach(*key)

    def close_network(self) -> None:
        """The run is over: every TCP unit stops listening and drops its clients."""
        for unit in self.units.values():
            if unit.tcp is not None:
                unit.tcp.close()

    # ------------------------------------------------------------ disk files
    def disk_path(self, spec: str, wildcards: bool = False) -> Path:
        """`unit:path\\name.ext` -> a path inside the sandbox (case-insensitive).
        With `wildcards` (FOPEND), the name may hold * and ?."""
        assert self.sandbox is not None
        match = re.fullmatch(r"(?:([A-Za-z]):)?([\\/]?(?:[^\\/:*?\"<>|]+[\\/])*)([^\\/:\"<>|]*)", spec.strip())
        if match is None or ".." in spec or (not wildcards and re.search(r"[*?]", match[3])):
            raise IoError(msg.INVALID_FILE_SPEC)
        unit, directory, name = match[1], match[2], match[3]
        base = self.sandbox / unit.upper() if unit else self.sandbox
        path = base
        for part in re.split(r"[\\/]", directory):
            if part:
                path = _existing_case(path, part)
        if name:
            stem, _, ext = name.partition(".")
            if not 1 <= len(stem) <= 8 or len(ext) > 3:
                raise IoError(msg.INVALID_FILE_SPEC)
            path = _existing_case(path, name)
        return _sandboxed(self.box.inside, path)

    def fopen(self, task: int, lun: int, mode: str, spec: str, record_length: int = 0, flags: int = 0,
              dialect: str = "eV+") -> None:
        unit = self.unit(task, lun)
        if unit.device != "DISK":
            raise IoError(msg.ILLEGAL_IO_COMMAND)
        if unit.file is not None:
            raise IoError(msg.FILE_ALREADY_OPEN)
        if self.open_files() >= MAX_OPEN_FILES:
            raise IoError(msg.DEVICE_NOT_READY)
        path = self.disk_path(spec, wildcards=mode == "D")
        self._check_shared(task, path, writing=mode in ("W", "A"))
        box = self.box
        handle = OpenFile(path, mode, record_length, random=bool(flags & RANDOM_ACCESS), box=box)
        if mode == "D":
            # FOPEND "path\" or "path\*.*" lists a folder; "path\*.TXT" filters it.
            folder, pattern = (path, "*") if path.is_dir() else (path.parent, path.name)
            if not folder.is_dir():
                raise IoError(msg.NONEXISTENT_FILE)
            entries = [p for p in _sandboxed(box.entries, folder) if fnmatch.fnmatch(p.name.lower(), pattern.lower())]
            record = _directory_record_v if dialect == "V+" else _directory_record_ev
            handle.data = b"".join(record(p) + b"\r\n" for p in entries)
        elif mode == "R":
            if not path.is_file():
                raise IoError(msg.NONEXISTENT_FILE)
            handle.data = _sandboxed(box.read_bytes, path)
        elif mode == "W":
            if path.exists():
                raise IoError(msg.FILE_EXISTS)  # disk files are never overwritten
            _sandboxed(box.make_folders, path.parent)
            _sandboxed(box.write_bytes, path, b"", "xb")
        else:  # A
            _sandboxed(box.make_folders, path.parent)
            _sandboxed(box.write_bytes, path, b"", "ab")
            handle.data = _sandboxed(box.read_bytes, path)
            handle.position = len(handle.data)
        unit.file = handle

    def _check_shared(self, task: int, path: Path, writing: bool) -> None:
        """"While a file is open for write or append access, another control program task
        cannot access that file"; several tasks may read it ([000] L7689-7691, [001] L3118).
        The guides give no code: *File already open*."""
        for (other, _lun), unit in self.units.items():
            held = unit.file
            if other != task and held is not None and held.path == path and (writing or held.mode in ("W", "A")):
                raise IoError(msg.FILE_ALREADY_OPEN)

    def open_network(self, task: int, lun: int, spec: str) -> None:
        """FOPEN on a TCP unit: a server (/LOCAL_PORT) or a client (/REMOTE_PORT)."""
        unit = self.unit(task, lun)
        if unit.tcp is None:
            raise IoError(msg.ILLEGAL_IO_COMMAND)  # graphics windows are absent
        if unit.tcp.opened:
            raise IoError(msg.FILE_ALREADY_OPEN)
        unit.tcp.open(spec)

    def read_network(self, task: int, lun: int, wait: bool) -> tuple[str, int] | None:
        """READ on a TCP unit: (bytes, handle), IOSTAT 1, 100 or 101 (tcp.py); None
        while nothing has arrived and the READ waits."""
        unit = self.unit(task, lun)
        try:
            outcome = unit.tcp.read()
            if outcome is None and not wait:
                raise IoError(msg.NO_DATA)
        except IoError as err:
            self.status[(task, lun)] = err.code
            return "", 0
        if outcome is None:
            return None
        status, handle, data = outcome
        self.status[(task, lun)] = status
        self.last_length[(task, lun)] = len(data)
        return data.decode("latin-1"), handle

    def fclose(self, task: int, lun: int) -> None:
        unit = self.unit(task, lun)
        if unit.tcp is not None:
            unit.tcp.close()
            return
        if unit.file is None:
            raise IoError(msg.FILE_NOT_OPEN)
        unit.file = None

    def fdelete(self, task: int, lun: int, spec: str) -> None:
        unit = self.unit(task, lun)
        if unit.device != "DISK":
            raise IoError(msg.ILLEGAL_IO_COMMAND)
        path = self.disk_path(spec)
        if not path.is_file():
            raise IoError(msg.NONEXISTENT_FILE)
        self._check_shared(task, path, writing=True)
        path.unlink()

    def fseek(self, task: int, lun: int, record: int) -> None:
        handle = self._file(task, lun)
        if not handle.random or handle.record_length <= 0:
            raise IoError(msg.ILLEGAL_IO_COMMAND)
        handle.position = (record - 1) * handle.record_length

    def _file(self, task: int, lun: int) -> OpenFile:
        unit = self.unit(task, lun)
        if unit.file is None:
            raise IoError(msg.FILE_NOT_OPEN)
        return unit.file

    # ------------------------------------------------------------ records
    def write(self, task: int, lun: int, text: str, newline: bool, record: int = 0) -> None:
        data = text.encode("latin-1", errors="replace")
        unit = self.units.get((task, lun))
        if unit is None and lun == TERMINAL_LUN:
            unit = Unit("TERMINAL")  # the terminal need not be attached for output
        if unit is None:
            raise IoError(msg.NOT_ATTACHED)
        if unit.device == "TERMINAL":
            self.console.write(text + ("\n" if newline else ""))
        elif unit.serial is not None:
            unit.serial.sent += data + (b"\r\n" if newline else b"")
        elif unit.tcp is not None:
            unit.tcp.write(record, data + (b"\r\n" if newline else b""))
        else:
            self._write_file(task, lun, data, newline, record)
        self.last_length[(task, lun)] = len(data)

    def _write_file(self, task: int, lun: int, data: bytes, newline: bool, record: int) -> None:
        handle = self._file(task, lun)
        if handle.mode not in ("W", "A"):
            raise IoError(msg.ILLEGAL_IO_COMMAND)
        if handle.record_length > 0:
            # Fixed-length records: padded with zero bytes or cut; /S does nothing.
            data = data[: handle.record_length].ljust(handle.record_length, b"\0")
            if handle.random and record > 0:
                handle.position = (record - 1) * handle.record_length
            content = bytearray(_sandboxed(self.box.read_bytes, handle.path))
            content.extend(b"\0" * max(handle.position - len(content), 0))
            end = handle.position + len(data)
            content[handle.position : end] = data
            _sandboxed(self.box.write_bytes, handle.path, bytes(content))
            handle.position = end
            return
        _sandboxed(self.box.write_bytes, handle.path, data + (b"\r\n" if newline else b""), "ab")

    def read_record(self, task: int, lun: int, record: int = 0) -> str | None:
        """The next record, or None while a serial line has no complete line yet."""
        unit = self.units.get((task, lun))
        if unit is None:
            raise IoError(msg.NOT_ATTACHED)
        if unit.device == "TERMINAL":
            line = self.console.read_line()
            if line is None:
                raise IoError(msg.UNEXPECTED_EOF)
            return line
        if unit.serial is not None:
            unit.serial.take_error()
            buffer = unit.serial.received
            end = buffer.find(b"\n")
            if end < 0:
                return None
            raw = bytes(buffer[:end])
            del buffer[: end + 1]
            text = raw.rstrip(b"\r").decode("latin-1")
            self.last_length[(task, lun)] = len(text)
            return text
        handle = self._file(task, lun)
        data = handle.content()
        if handle.record_length > 0:
            if handle.random and record > 0:
                handle.position = (record - 1) * handle.record_length
            if handle.position >= len(data):
                raise IoError(msg.UNEXPECTED_EOF)
            chunk = data[handle.position : handle.position + handle.record_length]
            handle.position += handle.record_length
            text = chunk.ljust(handle.record_length, b"\0").decode("latin-1")
        else:
            rest = data[handle.position :]
            if not rest or rest[0] == CTRL_Z:
                raise IoError(msg.UNEXPECTED_EOF)
            end = rest.find(b"\n")
            raw = rest if end < 0 else rest[:end]
            raw = raw.split(bytes([CTRL_Z]), 1)[0]
            handle.position += len(rest) if end < 0 else end + 1
            text = raw.rstrip(b"\r")[:RECORD_MAX].decode("latin-1")
        self.last_length[(task, lun)] = len(text)
        return text

    def wait_for_byte(self, rt, lun):
        """Before a step with GETC(lun) in wait mode: wait while the unit is a
        serial line with nothing received (any other case GETC answers at once)."""
        unit = self.units.get((rt.number, to_int(lun)))
        while unit is not None and unit.serial is not None and not (unit.serial.received or unit.serial.errors):
            yield rt.SLICE
        while unit is not None and unit.tcp is not None and not unit.tcp.has_byte():
            yield NETWORK_CYCLE  # the network is polled once per cycle

    def getc(self, task: int, lun: int) -> int:
        """GETC: the next byte, CR, LF and Ctrl-Z included, or a negative error code."""
        try:
            unit = self.unit(task, lun)
            if unit.serial is not None:
                unit.serial.take_error()
                if not unit.serial.received:
                    # No-wait mode, or a GETC whose step could not wait first.
                    raise IoError(msg.NO_DATA)
                byte = unit.serial.received.pop(0)
            elif unit.tcp is not None:
                byte = unit.tcp.getc()
                if byte is None:
                    raise IoError(msg.NO_DATA)
            elif unit.device == "TERMINAL":
                if not self.typed:
                    line = self.console.read_line()  # the terminal hands over whole lines
                    if line is None:
                        raise IoError(msg.UNEXPECTED_EOF)
                    self.typed += (line + "\r").encode("latin-1", errors="replace")
                byte = self.typed.pop(0)
            else:
                handle = self._file(task, lun)
                data = handle.content()
                if handle.position >= len(data):
                    raise IoError(msg.UNEXPECTED_EOF)
                byte = data[handle.position]
                handle.position += 1
        except IoError as err:
            self.status[(task, lun)] = err.code
            return err.code
        self.status[(task, lun)] = 1
        return byte


def _sandboxed(operation, *args):
    """A sandbox operation; a refused path is the program's *Invalid file specification*."""
    try:
        return operation(*args)
    except SandboxError:
        raise IoError(msg.INVALID_FILE_SPEC) from None


def _existing_case(folder: Path, name: str) -> Path:
    """DOS names are case-insensitive: reuse an entry that differs only in case."""
    if folder.is_dir():
        for entry in folder.iterdir():
            if entry.name.lower() == name.lower():
                return entry
    return folder / name.lower()


def _directory_fields(path: Path) -> tuple[str, str, int]:
    """(NAME, EXT, size in 512-byte sectors); attributes are "D" or blank."""
    stem, _, ext = path.name.upper().partition(".")
    sectors = 0 if path.is_dir() else -(-path.stat().st_size // 512)
    return stem, ext, sectors


def _directory_record_v(path: Path) -> bytes:
    """One FOPEND record in the V+ layout (V+ guide v17, "Disk Directory Format"):
    name (8), ".", extension (3), size in sectors (8, right-justified), space,
    attributes (7), date (9), space, time (8).  The date and time are blank, as
    the controller leaves them when its clock was never set."""
    stem, ext, sectors = _directory_fields(path)
    attributes = "D" if path.is_dir() else ""
    return f"{stem[:8]:<8}.{ext[:3]:<3}{sectors:>8} {attributes:<7}{'':9} {'':8}".encode("latin-1")


def _directory_record_ev(path: Path) -> bytes:
    """The eV+ layout ([001] "Disk Directory Format"): attributes (7), TAB, size
    in sectors (10, right-justified), TAB, date (9), TAB, time (8), TAB, then the
    name and extension; date and time blank as above."""
    stem, ext, sectors = _directory_fields(path)
    attributes = "D" if path.is_dir() else ""
    name = f"{stem}.{ext}" if ext else stem
    return f"{attributes:<7}\t{sectors:>10}\t{'':9}\t{'':8}\t{name}".encode("latin-1")
