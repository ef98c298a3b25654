"""`twin serve` as a test's peer, in a subprocess, on free ports (`--port P=0`: test runs
side by side never fight over 10100 or 11000); stopped with Ctrl-C (SIGINT).  `Tcs`: a raw
client of the TCP Command Server (one command line, one reply line)."""

from __future__ import annotations

import re
import signal
import socket
import subprocess
import sys
import threading
import time
from contextlib import contextmanager

LISTENING = re.compile(r"twin serve: listening on 127\.0\.0\.1:(\d+)(?: \(port (\d+) in the program\))?")


class Served:
    def __init__(self, process: subprocess.Popen):
        self.process = process
        self.lines: list[str] = []  # what twin serve printed on stderr so far
        self.returncode: int | None = None
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.process.stderr:
            self.lines.append(line)

    @property
    def stderr(self) -> str:
        return "".join(self.lines)

    def port(self, program_port: int, timeout: float = 60.0) -> int:
        """The real port the program's `program_port` listens on, once it does."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in list(self.lines):
                match = LISTENING.match(line)
                if match and int(match[2] or match[1]) == program_port:
                    return int(match[1])
            if self.process.poll() is not None:
                time.sleep(0.2)  # let the reader take the last lines
                raise RuntimeError(f"twin serve ended: {self.stderr}")
            time.sleep(0.02)
        raise RuntimeError(f"port {program_port} never listened: {self.stderr}")


@contextmanager
def serving(arguments: list[str], program_ports: list[int]):
    """`twin serve ARGUMENTS` with each of `program_ports` moved to a free port, until the
    block ends; yields a Served (its stderr and returncode are final after the block)."""
    moves = [item for port in program_ports for item in ("--port", f"{port}=0")]
    process = subprocess.Popen([sys.executable, "-m", "twin.cli", "serve", *arguments, *moves],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    served = Served(process)
    try:
        for port in program_ports:
            served.port(port)
        yield served
        process.send_signal(signal.SIGINT)
        process.wait(timeout=60)
        time.sleep(0.2)  # the reader's last lines
        served.returncode = process.returncode
    finally:
        if process.poll() is None:
            process.kill()


class Tcs:
    """A raw TCS client: `tcs("wherej")` sends the line and returns the reply line."""

    def __init__(self, port: int):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=60)
        self.lines = self.sock.makefile("rb")

    def __call__(self, command: str) -> str:
        self.sock.sendall(command.encode() + b"\n")
        line = self.lines.readline()
        assert line.endswith(b"\r\n"), line
        return line[:-2].decode()

    def close(self) -> None:
        self.sock.sendall(b"exit\n")
        assert self.lines.readline() == b""  # exit: closed without a reply
        self.sock.close()


def numbers(reply: str) -> list[float]:
    """The data of a successful reply as numbers."""
    code, *data = reply.split()
    assert code == "0", reply
    return [float(v) for v in data]
