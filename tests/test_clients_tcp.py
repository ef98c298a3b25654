"""The V+ TCP device (twin/language/vplus/tcp.py) as V+ servers and clients use it.

The peer is driven from the cycle hook of the interpreter-only runner, so each test
is deterministic: the peer acts at given cycles, the program sees it at the next one.
"""

from __future__ import annotations

import socket
import struct

import pytest

from twin.language.vplus import messages as msg
from twin.controller.network import listening
from twin.language.vplus.tcp import loopback

from vplus_helpers import run_vplus


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class ScriptedPeer:
    """A loopback client that connects, sends and closes at given cycles."""

    def __init__(self, port: int, script: list[tuple[int, str, bytes]]):
        self.port, self.script, self.cycle = port, sorted(script, key=lambda s: s[0]), 0
        self.sock: socket.socket | None = None
        self.received = bytearray()

    def __call__(self, system) -> None:
        self.cycle += 1
        for at, action, data in self.script:
            if at != self.cycle:
                continue
            if action == "connect":
                self.sock = socket.create_connection(("127.0.0.1", self.port))
                self.sock.setblocking(False)
            elif action == "send":
                self.sock.sendall(data)
            elif action == "close":
                self.take()
                self.sock.close()
        self.take()

    def take(self) -> None:
        if self.sock is None or self.sock.fileno() < 0:
            return
        try:
            while chunk := self.sock.recv(4096):
                self.received += chunk
        except BlockingIOError:
            pass


ECHO = """
.PROGRAM echo()
    AUTO lun, handle, st, $in, served
    ATTACH (lun, 4) "TCP"
    FOPEN (lun, 16) "/LOCAL_PORT {port} /CLIENTS 1 /BUFFER_SIZE 256"
    served = 0
    WHILE served < {clients} DO
        READ (lun, handle, 0) $in
        st = IOSTAT(lun)
        TYPE st, " ", handle, " ", LEN($in)
        IF st == 1 THEN
            WRITE (lun, handle) $LNGB(LNGB($in, 1) + 1), /S
        END
        IF st == 101 THEN
            served = served + 1
        END
    END
    FCLOSE (lun)
    DETACH (lun)
.END
"""


def test_server_reports_connections_data_and_closes_then_serves_the_next_client():
    port = free_port()
    first = ScriptedPeer(port, [(2, "connect", b""), (4, "send", struct.pack(">i", 41)), (8, "close", b"")])
    second = ScriptedPeer(port, [(12, "connect", b""), (13, "send", struct.pack(">i", -7)), (20, "close", b"")])

    def both(system):
        first(system)
        second(system)

    system, task = run_vplus(ECHO.format(port=port, clients=2), each_cycle=both, max_cycles=200)
    assert task.error is None
    lines = system.console.output.split()
    assert lines == ["100", "1", "0", "1", "1", "4", "101", "1", "0",
                     "100", "1", "0", "1", "1", "4", "101", "1", "0"]
    assert struct.unpack(">i", bytes(first.received)) == (42,)
    assert struct.unpack(">i", bytes(second.received)) == (-6,)
    assert port not in listening  # FCLOSE stopped listening


def test_bytes_sent_in_one_cycle_are_seen_at_the_next_cycle():
    port = free_port()
    text = f"""
.PROGRAM t()
    ATTACH (lun, 4) "TCP"
    FOPEN (lun, 16) "/LOCAL_PORT {port} /CLIENTS 2"
    READ (lun, h, 0) $in
    t0 = TIMER(-3)
    READ (lun, h, 0) $in
    TYPE IOSTAT(lun), " ", $in, " ", INT((TIMER(-3) - t0) / 0.016 + 0.5)
.END
"""
    peer = ScriptedPeer(port, [(3, "connect", b""), (10, "send", b"hello")])
    system, task = run_vplus(text, each_cycle=peer, max_cycles=100)
    assert task.error is None
    # Connection seen at cycle 3's run (the hook runs before the cycle); data sent
    # before cycle 10 is read in cycle 10: 7 cycles later.
    assert system.console.output.split() == ["1", "hello", "7"]


def test_no_wait_read_gives_no_data_and_leaves_the_string():
    port = free_port()
    text = f"""
.PROGRAM t()
    ATTACH (lun, 4) "TCP"
    FOPEN (lun, 16) "/LOCAL_PORT {port}"
    $in = "old"
    READ (lun, h, 1) $in
    TYPE IOSTAT(lun), " ", $in, " ", $ERROR(IOSTAT(lun))
.END
"""
    system, task = run_vplus(text, max_cycles=10)
    assert task.error is None
    assert system.console.output.strip() == f"{msg.NO_DATA} old *No data received*"


def test_client_that_disconnects_mid_message_leaves_the_server_serving():
    """The server reads 8-byte messages; the first client sends 5 bytes and leaves."""
    port = free_port()
    text = f"""
.PROGRAM t()
    ATTACH (lun, 4) "TCP"
    FOPEN (lun, 16) "/LOCAL_PORT {port} /CLIENTS 1"
    $buf = ""
    done = FALSE
    WHILE NOT done DO
        READ (lun, h, 0) $in
        CASE IOSTAT(lun) OF
          VALUE 1:
            $buf = $buf + $in
            IF LEN($buf) >= 8 THEN
                WRITE (lun, h) $FLTB(FLTB($buf, 1) + FLTB($buf, 5)), /S
                done = TRUE
            END
          VALUE 101:
            TYPE "dropped ", LEN($buf)
            $buf = ""
        END
    END
.END
"""
    half = ScriptedPeer(port, [(2, "connect", b""), (3, "send", struct.pack(">f", 1.5)[:3] + b"\x00\x00"),
                               (5, "close", b"")])
    full = ScriptedPeer(port, [(3, "connect", b""), (8, "send", struct.pack(">ff", 1.5, 2.25)),
                               (15, "close", b"")])

    def both(system):
        half(system)
        full(system)

    system, task = run_vplus(text, each_cycle=both, max_cycles=100)
    full.take()  # what the server wrote before its program ended
    assert task.error is None
    assert system.console.output.split() == ["dropped", "5"]
    assert struct.unpack(">f", bytes(full.received)) == (3.75,)


def test_getc_reads_the_current_client_byte_by_byte():
    port = free_port()
    text = f"""
.PROGRAM t()
    ATTACH (lun, 4) "TCP"
    FOPEN (lun, 16) "/LOCAL_PORT {port}"
    READ (lun, h, 0) $in
    c = GETC(lun)
    d = GETC(lun)
    e = GETC(lun, 1)
    TYPE c, " ", d, " ", e
.END
"""
    peer = ScriptedPeer(port, [(2, "connect", b""), (6, "send", b"AB")])
    system, task = run_vplus(text, each_cycle=peer, max_cycles=100)
    assert task.error is None
    assert system.console.output.split() == ["65", "66", str(msg.NO_DATA)]


def test_client_connects_to_a_loopback_server_and_sees_it_close():
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    port = server.getsockname()[1]
    text = f"""
.PROGRAM t()
    ATTACH (lun, 4) "TCP"
    FOPEN (lun) "/ADDRESS 127.0.0.1 /REMOTE_PORT {port}"
    TYPE IOSTAT(lun)
    WRITE (lun) $INTB(513), /S
    READ (lun, h) $in
    TYPE IOSTAT(lun), " ", $in
    READ (lun, h) $in
    TYPE IOSTAT(lun)
.END
"""
    state = {}

    def peer(system):
        if "conn" not in state:
            server.setblocking(False)
            try:
                state["conn"], _ = server.accept()
            except BlockingIOError:
                return
            state["conn"].setblocking(True)
            state["got"] = state["conn"].recv(2)
            state["conn"].sendall(b"ok")
            state["conn"].close()

    try:
        system, task = run_vplus(text, each_cycle=peer, max_cycles=100)
    finally:
        server.close()
    assert task.error is None
    assert state["got"] == b"\x02\x01"
    assert system.console.output.split() == ["1", "1", "ok", str(msg.NETWORK_CLOSED)]


@pytest.mark.parametrize("address", ["192.168.0.2", "10 0 0 1", "'robot.example.com'"])
def test_a_non_loopback_address_is_refused_before_any_socket(address):
    text = f"""
.PROGRAM t()
    ATTACH (lun, 4) "TCP"
    FOPEN (lun) "/ADDRESS {address} /REMOTE_PORT 11000"
.END
"""
    system, task = run_vplus(text, max_cycles=10)
    assert task.error is not None
    assert task.error.code == msg.NETWORK_REFUSED
    assert "*Network address not allowed*" in str(task.error)
    assert "loopback" in str(task.error) and task.error.line == 4


def test_loopback_names():
    assert loopback("localhost") == "127.0.0.1"
    assert loopback("127 0 0 1") == "127.0.0.1"
    assert loopback("127.0.0.5") == "127.0.0.5"
