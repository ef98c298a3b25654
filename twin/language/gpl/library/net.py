"""TCP and UDP (User Manual ch. 13, L2227-2566): IPEndPoint, Socket, TcpClient,
TcpListener, UdpClient, on real operating-system sockets limited to loopback.

Decisions (docs/gpl.md):
* The twin is one host on a closed network: an address a program names must be
  loopback (127.x.x.x, "localhost", "::1") or "any" ("", "0.0.0.0"), and is used
  as 127.0.0.1; ports are used as given.  Any other address (a peer such as
  192.168.0.2) is refused with -3120 *Socket error* when the socket would use
  it (connect, send, bind, Modbus), so a program reaches nothing beyond the
  twin's loopback (docs/robustness.md).  The manual's client and server
  examples talk to each other, or to a test's peer, on 127.0.0.1.
  ``IPEndPoint.IPAddress`` still reads back what was set.
* Calls that wait (Receive, ReceiveFrom, AcceptSocket) give the scheduler back
  every cycle until data or a connection is there, so other threads and the
  robot go on; their timeouts (``ReceiveTimeout``, ms, 0 = none) run in
  simulated time.  Connecting on loopback completes at once (the kernel
  accepts for a listening socket), so ``New TcpClient(ep)`` and ``Connect``
  do not wait; a refused connection raises -3120.
* Strings are byte buffers (one character per byte, Latin-1).  ``Send`` and
  ``SendTo`` with a length of 0 send the whole String (the manual's examples
  pass 0, L2474).
"""

from __future__ import annotations

import ipaddress
import select
import socket

from ....controller.network import listening, real_port
from . import codes
from . import byref, gpl_class
from .members import stored
from .thread import wait_ms
from ....controller.watchdog import external

LOOPBACK = "127.0.0.1"
ANY_ADDRESS = ("", "0.0.0.0", "::")
RECEIVE_CHUNK = 65536


def _bytes(text) -> bytes:
    return str(text).encode("latin-1")


def _text(data: bytes) -> str:
    return data.decode("latin-1")


def _readable(sock: socket.socket) -> bool:
    return bool(select.select([sock], [], [], 0)[0])


@gpl_class("IPEndPoint")
class IPEndPoint:
    def __init__(self, rt, address="", port=0):
        self._address = str(address)
        self.Port = int(port)

    IPAddress = stored("_address", str)

    @property
    def Port(self) -> int:
        return self._port

    @Port.setter
    def Port(self, value) -> None:
        value = int(value)
        if not 0 <= value <= 65535:
            raise codes.fail(codes.INVALID_ARGUMENT, f"port {value}")
        self._port = value

    def address(self) -> tuple[str, int]:
        """The loopback address the twin uses for this endpoint (its port as mapped); a
        non-loopback address is refused (the twin simulates a closed network)."""
        if not _loopback(self._address):
            raise codes.fail(codes.INVALID_NETWORK_ADDRESS, f"{self._address} is not a loopback address "
                             "(the twin is a closed network: use 127.0.0.1)")
        return LOOPBACK, real_port(self._port)


def _loopback(address: str) -> bool:
    text = address.strip()
    if text in ANY_ADDRESS or text.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(text).is_loopback
    except ValueError:  # a host name: the closed network resolves none but localhost
        return False


def _endpoint(rt, value) -> IPEndPoint:
    return codes.object_arg(value, IPEndPoint, "an IPEndPoint")


def _socket_error(err: OSError) -> Exception:
    return codes.fail(codes.SOCKET_ERROR, err.strerror or str(err))


@gpl_class("Socket")
class Socket:
    """A connected TCP socket or a UDP socket; made by TcpClient, TcpListener or UdpClient."""

    def __init__(self, rt, sock: socket.socket | None = None):
        if not isinstance(sock, socket.socket):
            raise codes.fail(codes.INVALID_ARGUMENT, "Socket objects come from TcpClient, TcpListener or UdpClient")
        self._rt = rt
        self._sock = sock
        sock.setblocking(False)
        self._blocking = True
        self._receive_timeout = 0.0
        self._send_timeout = 0.0
        self._remote: IPEndPoint | None = None

    Blocking = stored("_blocking", bool)
    ReceiveTimeout = stored("_receive_timeout", float)
    SendTimeout = stored("_send_timeout", float)  # sends on loopback never wait

    def _s(self) -> socket.socket:
        if self._sock is None:
            raise codes.fail(codes.SOCKET_NOT_OPEN, "the socket is closed")
        return self._sock

    @property
    def Available(self) -> int:
        sock = self._s()
        if not _readable(sock):
            return 0
        try:
            return len(sock.recv(RECEIVE_CHUNK, socket.MSG_PEEK))
        except OSError:
            return 0

    @property
    def KeepAlive(self) -> bool:
        return bool(self._s().getsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE))

    @KeepAlive.setter
    def KeepAlive(self, value) -> None:
        self._s().setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1 if value else 0)

    @property
    def RemoteEndPoint(self) -> IPEndPoint | None:
        return self._remote

    def Close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def Connect(self, endpoint) -> None:
        endpoint = _endpoint(self._rt, endpoint)
        sock = self._s()
        try:
            sock.setblocking(True)
            sock.settimeout(5.0)  # loopback: refused or accepted at once
            sock.connect(endpoint.address())
        except OSError as err:
            raise _socket_error(err) from None
        finally:
            sock.setblocking(False)
        self._remote = endpoint

    def _wait_readable(self):
        """Wait (simulated time) until the socket has data or an end; False on timeout."""
        sock = self._s()
        if _readable(sock):
            return True
        if not self._blocking:
            raise codes.fail(codes.SOCKET_TIMEOUT, "no data (non-blocking socket)")
        timeout = self._receive_timeout
        yield from wait_ms(self._rt, timeout if timeout > 0 else -1, until=external(lambda: _readable(sock)))
        if not _readable(sock):
            raise codes.fail(codes.SOCKET_TIMEOUT, f"nothing received in {timeout:g} ms")
        return True

    @byref(0)
    def Receive(self, buffer, max_length=RECEIVE_CHUNK):
        """Wait for data; put up to max_length bytes in `buffer`; returns the count
        (0 when the peer has closed the connection, L2350)."""
        yield from self._wait_readable()
        try:
            data = self._s().recv(max(int(max_length), 1))
        except OSError as err:
            raise _socket_error(err) from None
        buffer.value = _text(data)
        return len(data)

    @byref(0, 2)
    def ReceiveFrom(self, buffer, max_length, endpoint):
        """A datagram: its bytes in `buffer`, the sender in `endpoint`; returns the count."""
        yield from self._wait_readable()
        try:
            data, (host, port) = self._s().recvfrom(max(int(max_length), 1))
        except OSError as err:
            raise _socket_error(err) from None
        buffer.value = _text(data)
        endpoint.value = IPEndPoint(self._rt, host, port)
        return len(data)

    def Send(self, buffer, length=0) -> int:
        data = _bytes(buffer)
        if int(length) > 0:
            data = data[: int(length)]
        sock = self._s()
        try:
            sock.setblocking(True)  # loopback: the kernel buffers it at once
            sock.sendall(data)
        except OSError as err:
            raise _socket_error(err) from None
        finally:
            sock.setblocking(False)
        return len(data)

    def SendTo(self, buffer, length, endpoint) -> int:
        data = _bytes(buffer)
        if int(length) > 0:
            data = data[: int(length)]
        try:
            return self._s().sendto(data, _endpoint(self._rt, endpoint).address())
        except OSError as err:
            raise _socket_error(err) from None


@gpl_class("TcpClient")
class TcpClient:
    def __init__(self, rt, endpoint=None):
        self._rt = rt
        self._client = Socket(rt, socket.socket(socket.AF_INET, socket.SOCK_STREAM))
        if endpoint is not None:
            self._client.Connect(endpoint)

    Client = stored("_client", readonly=True)

    def Close(self) -> None:
        self._client.Close()


@gpl_class("TcpListener")
class TcpListener:
    """Listens on the endpoint's port (the address is always loopback)."""

    def __init__(self, rt, endpoint):
        self._rt = rt
        self._endpoint = _endpoint(rt, endpoint)
        self._sock: socket.socket | None = None

    def Start(self) -> None:
        if self._sock is not None:
            return
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind(self._endpoint.address())
            sock.listen(8)
        except OSError as err:
            sock.close()
            raise _socket_error(err) from None
        sock.setblocking(False)
        self._sock = sock
        listening[sock.getsockname()[1]] = self._endpoint.Port

    def _s(self) -> socket.socket:
        if self._sock is None:
            raise codes.fail(codes.SOCKET_ERROR, "the listener is not started")
        return self._sock

    def Pending(self) -> bool:
        return _readable(self._s())

    def AcceptSocket(self):
        """Wait for a connection request and accept it."""
        sock = self._s()
        if not _readable(sock):
            yield from wait_ms(self._rt, -1, until=external(lambda: _readable(sock)))
        try:
            conn, (host, port) = sock.accept()
        except OSError as err:
            raise _socket_error(err) from None
        accepted = Socket(self._rt, conn)
        accepted._remote = IPEndPoint(self._rt, host, port)
        return accepted

    def Stop(self) -> None:
        if self._sock is not None:
            listening.pop(self._sock.getsockname()[1], None)
            self._sock.close()
            self._sock = None

    Close = Stop


@gpl_class("UdpClient")
class UdpClient:
    def __init__(self, rt, endpoint=None):
        self._rt = rt
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        port = _endpoint(rt, endpoint).address()[1] if endpoint is not None else 0
        try:
            sock.bind((LOOPBACK, real_port(port) if port else 0))
        except OSError as err:
            sock.close()
            raise _socket_error(err) from None
        self._client = Socket(rt, sock)

    Client = stored("_client", readonly=True)

    def Close(self) -> None:
        self._client.Close()
