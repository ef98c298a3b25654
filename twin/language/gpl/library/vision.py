"""Vision guidance (User Manual ch. 16, L3086-3220): the Vision and VisResult classes, a
client of the twin's built-in vision server (twin/vision/server.py) over TCP port 1410,
as GPL is a client of PreciseVision.

Decisions (docs/vision.md):
* Any IPAddress reaches the twin's own server (the twin is one host, as for the TCP
  classes): the address a program sets, or "Vision server IP address" (DataID 424), is
  kept and reads back, but the connection goes to the server's loopback address.
* Process, Result and ResultCount connect when there is no connection (L3167); a
  connection that cannot be made raises -3120.  Process waits, in simulated time, until
  the server's results are ready (the modelled processing time); a server that would take
  more than 30 s raises -3121 (L3169).
* A process that fails (no such process, camera not calibrated) does not raise: Status is
  2 and ErrorCode says why, as Table 16-2 describes.  ResultCount of a tool the process
  does not have raises; Result returns a VisResult whose ErrorCode says what went wrong.
* VisResult.Info(n) is 1-based: 1 x, 2 y (mm), 3 angle (deg), 4 score, 5 area (mm^2),
  6 width, 7 length (mm); InfoString is the model the pattern tool matched.
"""

from __future__ import annotations

import socket

from ....controller.location import Location
from . import codes, gpl_class
from .locations import GplLocation
from .members import stored
from .thread import wait_ms

REPLY_TIMEOUT_S = 30.0  # L3169
INFO_COUNT = 7


def _server(rt):
    server = getattr(rt.system, "vision", None)
    if server is None:
        raise codes.fail(codes.VISION_CONNECT, "no vision server in this cell (the cell file has no [vision])")
    return server


@gpl_class("Vision")
class Vision:
    def __init__(self, rt, *args):
        if args:
            raise codes.fail(codes.INVALID_ARGUMENT, "New Vision takes no arguments")
        self._rt = rt
        self._sock: socket.socket | None = None
        self._buffer = b""
        self._address = "127.0.0.1"
        self._instance = 1
        self._status = 0
        self._error = 0

    IPAddress = stored("_address", str)
    Instance = stored("_instance", int)
    Status = stored("_status", readonly=True)
    ErrorCode = stored("_error", readonly=True)

    # ---- the connection
    def _request(self, *words) -> list[str]:
        """Send one request line, let the server answer it, read the reply's fields."""
        server = _server(self._rt)
        if self._sock is None:
            try:
                self._sock = socket.create_connection(server.address, timeout=REPLY_TIMEOUT_S)
            except OSError as err:
                raise codes.fail(codes.VISION_CONNECT, f"vision server: {err.strerror or err}") from None
        self._sock.sendall(("\t".join(str(w) for w in words) + "\n").encode("latin-1"))
        server.serve()
        while b"\n" not in self._buffer:
            chunk = self._sock.recv(65536)
            if not chunk:
                self.Disconnect()
                raise codes.fail(codes.CONNECTION_CLOSED, "the vision server closed the connection")
            self._buffer += chunk
        line, self._buffer = self._buffer.split(b"\n", 1)
        return line.decode("latin-1").split("\t")

    def Disconnect(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None
            self._buffer = b""

    # ---- members
    def Process(self, name, process_id=None):
        """Run a vision process and wait until its results are ready."""
        reply = self._request("PROCESS", str(name))
        if reply[0] != "OK":
            self._status, self._error = 2, int(reply[1])
            return
        ready_at = float(reply[2])
        wait = ready_at - self._rt.clock()
        if wait > REPLY_TIMEOUT_S:
            raise codes.fail(codes.SOCKET_TIMEOUT, f"vision process {name!r} takes {wait:g} s")
        self._status, self._error = 1, 0
        if wait > 0:
            yield from wait_ms(self._rt, wait * 1000.0)
        self._status = 3

    def ResultCount(self, tool="") -> int:
        """The results of `tool`; without one, of the process's default result (its last
        tool), as the TCP Command Server 3.0 asks `glbVision.ResultCount`."""
        reply = self._request("COUNT", str(tool))
        if reply[0] != "OK":
            raise codes.GplError(int(reply[1]), reply[2])
        return int(reply[1])

    def Result(self, tool="", index=1) -> "VisResult":
        reply = self._request("RESULT", str(tool), int(index))
        result = VisResult(self._rt)
        if reply[0] != "OK":
            result._error = int(reply[1])
            return result
        from ....vision.server import decode_instance

        fields = decode_instance(reply[1:])
        result._process_id = fields["process_id"]
        result._loc = GplLocation.cartesian(self._rt, Location(fields["x"], fields["y"], fields["z"],
                                                               fields["angle"], 0.0, 0.0))
        result._passed = bool(fields["passed"]) if fields["passed"] is not None else False
        result._actual = fields["actual"] if fields["actual"] is not None else 0.0
        result._text = fields["model"]
        result._info = fields["info"]
        return result

    def ToolProperty(self, tool, prop):
        reply = self._request("GET", str(tool), str(prop))
        if reply[0] != "OK":
            raise codes.GplError(int(reply[1]), reply[2])
        return _number_or_text(reply[1])

    def set_ToolProperty(self, tool, prop, value) -> None:
        reply = self._request("SET", str(tool), str(prop), value)
        if reply[0] != "OK":
            raise codes.GplError(int(reply[1]), reply[2])


def _number_or_text(text: str):
    try:
        return float(text)
    except ValueError:
        return text


@gpl_class("VisResult")
class VisResult:
    def __init__(self, rt, *args):
        if args:
            raise codes.fail(codes.INVALID_ARGUMENT, "New VisResult takes no arguments")
        self._rt = rt
        self._error = 0
        self._process_id = 0
        self._loc = GplLocation(rt)
        self._passed = False
        self._actual = 0.0
        self._text = ""
        self._info: list[float] = []

    ErrorCode = stored("_error", readonly=True)
    ProcessID = stored("_process_id", readonly=True)
    InspectPassed = stored("_passed", readonly=True)
    InspectActual = stored("_actual", readonly=True)
    InfoString = stored("_text", readonly=True)

    @property
    def Loc(self) -> GplLocation:
        return self._loc.Clone()

    @property
    def InfoCount(self) -> int:
        return len(self._info)

    @property
    def Type(self) -> int:
        return 0  # "Currently always zero" (Table 16-3)

    def Info(self, n) -> float:
        n = int(n)
        if not 1 <= n <= len(self._info):
            raise codes.fail(codes.INVALID_ARGUMENT, f"Info({n}): the result has {len(self._info)} fields")
        return self._info[n - 1]
