"""The V+ "TCP" device (AdeptTCP/IP, as V+ servers such as the ROS-Industrial
Adept driver use it), on real operating-system sockets limited to loopback.

    ATTACH (lun, 4) "TCP"
    FOPEN (lun, 16) "/LOCAL_PORT 11000 /CLIENTS 1 /BUFFER_SIZE 1024"   a server
    FOPEN (lun) "/ADDRESS 127.0.0.1 /REMOTE_PORT 9000"                 a client
    READ (lun, handle, mode) $data     any client's bytes; handle says whose
    WRITE (lun, handle) $reply, /S     to that client
    IOSTAT(lun)                        1 data, 100 a new client, 101 a client left,
                                       -526 no data (no-wait), -562 connection closed

Decisions (docs/clients.md):
* Loopback only: a server listens on 127.0.0.1, a client connects to a loopback
  address or `localhost`; any other address is refused with a program error
  before a socket is even made.
* Simulated time: the sockets are polled, without blocking, at most once per
  simulated instant (the scheduler's major cycle), when a TCP operation first
  needs them; a READ that finds nothing waits for the next cycle.  What a
  program sees depends only on the order in which bytes and connections
  arrived, not on wall-clock timing inside a cycle.
* A READ on a server reports, in this order: new connections (IOSTAT 100, the
  string empty, `handle` the new client), then data from the lowest handle
  that has some (at most /BUFFER_SIZE bytes and one string's 128), then a
  client that has closed once its data is read (IOSTAT 101).  Handles are the
  lowest free numbers from 1.  A client beyond /CLIENTS waits in the listen
  queue until one leaves.
* Codes 100 and 101 are the AdeptTCP/IP ones as we remember them; -562 for a
  closed connection is twin-chosen (the Reference Guide's numerical list was
  not found).
"""

from __future__ import annotations

import ipaddress
import re
import select
import socket
from dataclasses import dataclass, field
from typing import Callable

from ...controller.network import listening, real_port
from . import messages as msg
from .fileio import IoError
from .values import fail

CLOSE_CLIENT = 600  # FCMND (lun, 600) $INTB(handle), as the ROS-Industrial drivers call it
NEW_CONNECTION = 100
CONNECTION_CLOSED = 101
DEFAULT_BUFFER = 512
RECEIVE_CHUNK = 65536
OPTION = re.compile(r"/([A-Z_]+)\s*((?:'[^']*'|\"[^\"]*\"|[^/])*)", re.IGNORECASE)



def loopback(address: str) -> str:
    """The loopback address to use for `address`; any other is refused, before
    any socket exists, with a program error that says why."""
    text = address.strip().strip("'\"")
    if text.lower() == "localhost":
        return "127.0.0.1"
    dotted = ".".join(text.split()) if re.fullmatch(r"\d+(\s+\d+){3}", text) else text
    try:
        ip = ipaddress.ip_address(dotted)
    except ValueError:
        raise fail(msg.NETWORK_REFUSED, f"{text!r} is not an address the twin can reach "
                   "(it talks to loopback only: 127.0.0.1, localhost)") from None
    if not ip.is_loopback:
        raise fail(msg.NETWORK_REFUSED, f"{dotted}: the twin talks to loopback addresses only "
                   "(127.0.0.1, localhost); no packet was sent")
    return str(ip)


def _options(spec: str) -> dict[str, str]:
    options = {}
    for match in OPTION.finditer(spec):
        options[match[1].upper()] = match[2].strip()
    if not options:
        raise fail(msg.INVALID_ARGUMENT, f"TCP open string {spec!r}")
    return options


def _number(options: dict[str, str], name: str, default: int | None = None) -> int:
    text = options.get(name)
    if text is None:
        if default is None:
            raise fail(msg.INVALID_ARGUMENT, f"/{name} is missing")
        return default
    try:
        return int(text)
    except ValueError:
        raise fail(msg.INVALID_ARGUMENT, f"/{name} {text}") from None


@dataclass
class Connection:
    handle: int
    sock: socket.socket
    received: bytearray = field(default_factory=bytearray)
    closed: bool = False  # the peer has closed (or reset) it; its bytes may still wait

    def pull(self) -> None:
        """Take what the kernel holds, without waiting."""
        while not self.closed and select.select([self.sock], [], [], 0)[0]:
            try:
                data = self.sock.recv(RECEIVE_CHUNK)
            except OSError:
                data = b""
            if not data:
                self.closed = True
            self.received += data

    def send(self, data: bytes) -> None:
        try:
            self.sock.setblocking(True)  # loopback: the kernel takes it at once
            self.sock.sendall(data)
        except OSError:
            self.closed = True
            raise
        finally:
            if not self.closed:
                self.sock.setblocking(False)

    def close(self) -> None:
        self.sock.close()


class TcpEndpoint:
    """One attached TCP unit, opened as a server or as a client."""

    def __init__(self, clock: Callable[[], float]):
        self.clock = clock
        self.listener: socket.socket | None = None
        self.port = 0
        self.max_clients = 1
        self.buffer_size = DEFAULT_BUFFER
        self.connections: dict[int, Connection] = {}
        self.new: list[int] = []  # handles of new connections not yet reported
        self.server = False
        self.ever_opened = False
        self.current = 0  # the handle of the last READ (GETC reads from it)
        self._polled_at: float | None = None

    @property
    def opened(self) -> bool:
        return self.listener is not None or bool(self.connections)

    # ------------------------------------------------------------ open / close
    def open(self, spec: str) -> None:
        options = _options(spec)
        self.ever_opened = False
        self.buffer_size = max(1, _number(options, "BUFFER_SIZE", DEFAULT_BUFFER))
        if "LOCAL_PORT" in options:
            self._listen(_number(options, "LOCAL_PORT"), max(1, _number(options, "CLIENTS", 1)))
        elif "REMOTE_PORT" in options:
            address = options.get("ADDRESS") or options.get("NODE") or options.get("REMOTE_NAME")
            if address is None:
                raise fail(msg.INVALID_ARGUMENT, "/REMOTE_PORT needs /ADDRESS or /NODE")
            self._connect(loopback(address), _number(options, "REMOTE_PORT"))
        else:
            raise fail(msg.INVALID_ARGUMENT, f"TCP open string {spec!r} has neither /LOCAL_PORT nor /REMOTE_PORT")

    def _listen(self, port: int, clients: int) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind(("127.0.0.1", real_port(port)))
            sock.listen(8)
        except OSError:
            sock.close()
            raise IoError(msg.DEVICE_NOT_READY) from None  # the port is taken
        sock.setblocking(False)
        self.listener, self.port, self.max_clients, self.server = sock, sock.getsockname()[1], clients, True
        listening[self.port] = port
        self.ever_opened = True

    def _connect(self, address: str, port: int) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            sock.settimeout(5.0)  # loopback: refused or accepted at once
            sock.connect((address, real_port(port)))
        except OSError:
            sock.close()
            raise IoError(msg.NETWORK_CLOSED) from None
        sock.setblocking(False)
        self.connections[1] = Connection(1, sock)
        self.current = 1
        self.ever_opened = True

    def close(self) -> None:
        for connection in self.connections.values():
            connection.close()
        self.connections.clear()
        if self.listener is not None:
            listening.pop(self.port, None)
            self.listener.close()
            self.listener = None

    def command(self, code: int, data: str) -> None:
        """FCMND on a TCP unit.  600 with `$INTB(handle)`: close that client's
        connection and free its handle; after READ has reported the client gone
        (IOSTAT 101) the handle is free already and the command just succeeds,
        which is how servers use it.  Another number: *Illegal I/O device command*."""
        if code != CLOSE_CLIENT:
            raise IoError(msg.ILLEGAL_IO_COMMAND)
        raw = data.encode("latin-1", errors="replace")
        if len(raw) < 2 or not self.server:
            raise IoError(msg.INVALID_ARGUMENT)  # no handle given, or a client unit
        handle = int.from_bytes(raw[:2], "big", signed=True)
        if not 1 <= handle <= self.max_clients:
            raise IoError(msg.ILLEGAL_VALUE)
        connection = self.connections.pop(handle, None)
        if connection is not None:
            connection.close()
        if handle in self.new:
            self.new.remove(handle)

    # ------------------------------------------------------------ polling
    def poll(self) -> None:
        """Once per simulated instant: accept waiting clients, take arrived bytes."""
        now = self.clock()
        if now == self._polled_at:
            return
        self._polled_at = now
        while (self.listener is not None and len(self.connections) < self.max_clients
               and select.select([self.listener], [], [], 0)[0]):
            try:
                sock, _ = self.listener.accept()
            except OSError:
                break
            sock.setblocking(False)
            handle = next(h for h in range(1, self.max_clients + 2) if h not in self.connections)
            self.connections[handle] = Connection(handle, sock)
            self.new.append(handle)
        for handle in sorted(self.connections):
            self.connections[handle].pull()

    # ------------------------------------------------------------ I/O
    def read(self) -> tuple[int, int, bytes] | None:
        """(IOSTAT, handle, bytes) of the next thing a READ reports, or None: nothing yet."""
        if not self.opened and not self.new:
            raise IoError(msg.NETWORK_CLOSED if self.ever_opened else msg.FILE_NOT_OPEN)
        self.poll()
        if self.new:
            handle = self.new.pop(0)
            self.current = handle
            return NEW_CONNECTION, handle, b""
        limit = min(self.buffer_size, 128)
        for handle in sorted(self.connections):
            connection = self.connections[handle]
            if connection.received:
                data = bytes(connection.received[:limit])
                del connection.received[:limit]
                self.current = handle
                return 1, handle, data
        for handle in sorted(self.connections):
            connection = self.connections[handle]
            if connection.closed:
                connection.close()
                del self.connections[handle]
                if not self.server:
                    raise IoError(msg.NETWORK_CLOSED)
                return CONNECTION_CLOSED, handle, b""
        return None

    def getc(self) -> int | None:
        """The next byte of the current client, or None: none has arrived."""
        self.poll()
        connection = self.connections.get(self.current)
        if connection is None:  # no READ has chosen a client: the first with data, else one gone
            ordered = [c for _, c in sorted(self.connections.items())]
            candidates = [c for c in ordered if c.received] or [c for c in ordered if c.closed]
            connection = candidates[0] if candidates else None
        if connection is None or not connection.received:
            if connection is not None and connection.closed:
                raise IoError(msg.NETWORK_CLOSED)
            return None
        self.current = connection.handle
        return connection.received.pop(0)

    def has_byte(self) -> bool:
        self.poll()
        return any(c.received or c.closed for c in self.connections.values())

    def write(self, handle: int, data: bytes) -> None:
        # The network accepts clients whether or not the program READs: a
        # server that only sends (a feedback stream) sees its client connect.
        self.poll()
        connection = self.connections.get(handle)
        if connection is None and handle == 0 and len(self.connections) == 1:
            connection = next(iter(self.connections.values()))
        if connection is None or connection.closed:
            raise IoError(msg.NETWORK_CLOSED)
        try:
            connection.send(data)
        except OSError:
            raise IoError(msg.NETWORK_CLOSED) from None
