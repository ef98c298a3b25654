"""What the programs of this process do on the network, shared by both languages.

* `port_map`: a program's port -> the loopback port really used (0: any free one).  A
  server program names its port (11000, 10100 ...); `twin serve --port 10100=0`, or a
  test, moves it so that several twins (or test runs) can serve side by side.
* `listening`: the loopback ports the programs listen on now -> the port each program
  asked for (V+ TCP units, GPL TcpListener); `twin serve` prints them.
"""

from __future__ import annotations

port_map: dict[int, int] = {}
listening: dict[int, int] = {}


def real_port(port: int) -> int:
    """The loopback port to bind or connect to for a program's `port`."""
    return port_map.get(port, port)


def program_port(real: int) -> int | None:
    """The program's port for a port the twin listens on (None: not listening)."""
    return listening.get(real)


def listening_on(program: int) -> int | None:
    """The real port a program's server `program` port listens on now (None: not yet)."""
    for real, asked in listening.items():
        if asked == program:
            return real
    return None
