"""The Modbus class (User Manual ch. 14, L2571-2690): a Modbus/TCP master.

Decisions (docs/gpl.md):
* Addresses are loopback, like every socket of the twin (net.py); the port is
  the endpoint's, 502 when it is 0 (the standard port, L2614).
* Coil and register numbers in GPL are 1-based ("Coil 1" in the manual's
  example, L2652) and go on the wire as protocol addresses n - 1.
* The connection is made at the first request (L2624) and kept until Close.
  A request waits (giving the scheduler back every cycle) for the complete
  response; ``Timeout`` (ms, 0 = none, the default) runs in simulated time.
* An exception response raises -3130 with the Modbus exception code; a
  timeout raises -3131; a connection failure -3120.
* Read methods fill the ByRef array argument (allocated or not) with one
  element per item: Booleans for coils and inputs, Integers for registers.
"""

from __future__ import annotations

import select
import socket
import struct

from ..values import GplArray
from . import codes
from . import byref, gpl_class
from .members import stored
from .net import IPEndPoint, LOOPBACK
from .thread import wait_ms
from ....controller.watchdog import external

DEFAULT_PORT = 502
UNIT_ID = 1
READ_COILS, READ_DISCRETE_INPUTS, READ_HOLDING, READ_INPUT = 1, 2, 3, 4
WRITE_COIL, WRITE_REGISTER, WRITE_COILS, WRITE_REGISTERS = 5, 6, 15, 16
READ_DEVICE_ID = 43


def _items(array) -> list:
    if array is None:
        raise codes.fail(codes.NOTHING_ARGUMENT, "the array is Nothing")
    return list(array)


def _address(number) -> int:
    n = int(number)
    if not 1 <= n <= 65536:
        raise codes.fail(codes.INVALID_ARGUMENT, f"Modbus item {number} (1 to 65536)")
    return n - 1


@gpl_class("Modbus")
class Modbus:
    def __init__(self, rt, endpoint):
        if not isinstance(endpoint, IPEndPoint):
            raise codes.fail(codes.INVALID_ARGUMENT, "New Modbus needs an IPEndPoint")
        self._rt = rt
        endpoint.address()  # refuses a non-loopback device address (closed network)
        self._port = endpoint.Port or DEFAULT_PORT
        self._sock: socket.socket | None = None
        self._transaction = 0
        self._buffer = b""
        self._timeout = 0.0

    Timeout = stored("_timeout", float)

    # ------------------------------------------------------------ transport
    def _connect(self) -> socket.socket:
        if self._sock is None:
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.settimeout(5.0)  # loopback: refused or accepted at once
            try:
                sock.connect((LOOPBACK, self._port))
            except OSError as err:
                sock.close()
                raise codes.fail(codes.SOCKET_ERROR, f"Modbus connection: {err.strerror or err}") from None
            self._sock = sock
        return self._sock

    def _request(self, function: int, payload: bytes):
        """Send one request PDU and wait for its response PDU (without the function code)."""
        sock = self._connect()
        self._transaction = (self._transaction + 1) & 0xFFFF
        pdu = bytes([function]) + payload
        sock.sendall(struct.pack(">HHHB", self._transaction, 0, len(pdu) + 1, UNIT_ID) + pdu)
        timeout = self._timeout
        while True:
            frame = self._frame()
            if frame is not None:
                break
            yield from wait_ms(self._rt, timeout if timeout > 0 else -1,
                                until=external(lambda: bool(select.select([sock], [], [], 0)[0])))
            if not select.select([sock], [], [], 0)[0]:
                raise codes.fail(codes.MODBUS_TIMEOUT, f"no response in {timeout:g} ms")
            data = sock.recv(4096)
            if not data:
                self.Close()
                raise codes.fail(codes.CONNECTION_CLOSED, "the Modbus slave closed the connection")
            self._buffer += data
        transaction, _, _, _, answer = frame
        if answer[0] == function | 0x80:
            raise codes.fail(codes.MODBUS_EXCEPTION, f"function {function}, exception code {answer[1]}")
        if transaction != self._transaction or answer[0] != function:
            raise codes.fail(codes.SOCKET_ERROR, "unexpected Modbus response")
        return answer[1:]

    def _frame(self):
        """One complete response from the buffer: (transaction, protocol, length, unit, pdu)."""
        if len(self._buffer) < 7:
            return None
        transaction, protocol, length, unit = struct.unpack(">HHHB", self._buffer[:7])
        end = 6 + length
        if len(self._buffer) < end:
            return None
        pdu, self._buffer = self._buffer[7:end], self._buffer[end:]
        return transaction, protocol, length, unit, pdu

    def Close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None
        self._buffer = b""

    # ------------------------------------------------------------ reads
    def _read_bits(self, function: int, start, count, target):
        count = int(count)
        answer = yield from self._request(function, struct.pack(">HH", _address(start), count))
        bits = [bool(answer[1 + i // 8] >> (i % 8) & 1) for i in range(count)]
        target.value = GplArray.of(bits, False)

    def _read_registers(self, function: int, start, count, target):
        count = int(count)
        answer = yield from self._request(function, struct.pack(">HH", _address(start), count))
        values = list(struct.unpack(f">{count}H", answer[1: 1 + 2 * count]))
        target.value = GplArray.of(values, 0)

    @byref(2)
    def ReadCoils(self, start, count, bits):
        yield from self._read_bits(READ_COILS, start, count, bits)

    @byref(2)
    def ReadDiscreteInputs(self, start, count, bits):
        yield from self._read_bits(READ_DISCRETE_INPUTS, start, count, bits)

    @byref(2)
    def ReadHoldingRegisters(self, start, count, values):
        yield from self._read_registers(READ_HOLDING, start, count, values)

    @byref(2)
    def ReadInputRegisters(self, start, count, values):
        yield from self._read_registers(READ_INPUT, start, count, values)

    @byref(1)
    def ReadDeviceId(self, object_id, text):
        """Read Device Identification (function 43 / MEI 14), one object as a String."""
        answer = yield from self._request(READ_DEVICE_ID, bytes([14, 4, int(object_id)]))
        # MEI type, id code, conformity, more, next id, count, then (id, length, value)...
        count, pos = answer[5], 6
        for _ in range(count):
            oid, length = answer[pos], answer[pos + 1]
            if oid == int(object_id):
                text.value = answer[pos + 2: pos + 2 + length].decode("latin-1")
                return
            pos += 2 + length
        raise codes.fail(codes.MODBUS_EXCEPTION, f"no device id object {object_id}")

    # ------------------------------------------------------------ writes
    def WriteSingleCoil(self, coil, value):
        yield from self._request(WRITE_COIL, struct.pack(">HH", _address(coil), 0xFF00 if value else 0))

    def WriteSingleRegister(self, register, value):
        yield from self._request(WRITE_REGISTER, struct.pack(">HH", _address(register), int(value) & 0xFFFF))

    def WriteMultipleCoils(self, start, bits):
        values = [bool(v) for v in _items(bits)]
        packed = bytearray((len(values) + 7) // 8)
        for i, on in enumerate(values):
            if on:
                packed[i // 8] |= 1 << (i % 8)
        header = struct.pack(">HHB", _address(start), len(values), len(packed))
        yield from self._request(WRITE_COILS, header + bytes(packed))

    def WriteMultipleRegisters(self, start, values):
        registers = [int(v) & 0xFFFF for v in _items(values)]
        header = struct.pack(">HHB", _address(start), len(registers), 2 * len(registers))
        yield from self._request(WRITE_REGISTERS, header + struct.pack(f">{len(registers)}H", *registers))
