"""`twin serve` as a test's peer: started in a subprocess, stopped with Ctrl-C (SIGINT)."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
from contextlib import contextmanager


class Served:
    def __init__(self, process: subprocess.Popen):
        self.process = process
        self.stderr = ""  # what twin serve printed, once it has stopped
        self.returncode: int | None = None


def wait_for_port(process: subprocess.Popen, port: int) -> None:
    for _ in range(1200):
        if process.poll() is not None:
            raise RuntimeError(process.stderr.read())
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return
        except OSError:
            time.sleep(0.05)
    raise RuntimeError(f"twin serve never listened on {port}")


@contextmanager
def serving(arguments: list[str], port: int):
    """`twin serve ARGUMENTS` until the block ends, then Ctrl-C; yields a Served whose
    stderr and returncode are set after the block."""
    process = subprocess.Popen([sys.executable, "-m", "twin.cli", "serve", *arguments],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    served = Served(process)
    try:
        wait_for_port(process, port)
        yield served
        process.send_signal(signal.SIGINT)
        _, served.stderr = process.communicate(timeout=60)
        served.returncode = process.returncode
    finally:
        if process.poll() is None:
            process.kill()
