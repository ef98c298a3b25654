"""What the programs of this process do on the network, for `twin serve` to show.

Both languages' servers (V+ TCP units, GPL TcpListener) register the loopback ports
they listen on here while they listen.
"""

from __future__ import annotations

listening_ports: set[int] = set()
