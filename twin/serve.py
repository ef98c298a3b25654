"""`twin serve`: keep a cell running for the client software that drives it.

A server program (a V+ TCP server, a GPL TCP Command Server) waits for clients
on loopback ports; `serve_program` runs its cell with the simulated clock paced
to the wall clock (`fast`: as fast as it goes), prints each port the programs
start or stop listening on, and stops when the program ends or at Ctrl-C
(SIGINT, SIGTERM), then writes the report as `twin run` does.  The program
still lives on simulated time: clients' bytes are seen at the next major cycle
(docs/clients.md).
"""

from __future__ import annotations

import signal
import sys
import threading
import time
from pathlib import Path
from typing import Callable, TextIO

from .controller import network
from .runner import RunResult, finish_run, start_program


class Pacer:
    """Called after each major cycle: sleeps so that simulated time does not run
    ahead of `speed` x wall time, reports port changes, says when to stop."""

    def __init__(self, clock: Callable[[], float], fast: bool, speed: float, out: TextIO):
        self.clock, self.fast, self.speed, self.out = clock, fast, speed, out
        self.stop_requested = False
        self.ports: dict[int, int] = {}
        self._start_wall = time.perf_counter()
        self._start_sim = clock()

    def __call__(self) -> bool:
        if network.listening != self.ports:
            for port in sorted(set(network.listening) - set(self.ports)):
                asked = network.listening[port]
                moved = "" if asked == port else f" (port {asked} in the program)"
                print(f"twin serve: listening on 127.0.0.1:{port}{moved}", file=self.out, flush=True)
            for port in sorted(set(self.ports) - set(network.listening)):
                print(f"twin serve: closed 127.0.0.1:{port}", file=self.out, flush=True)
            self.ports = dict(network.listening)
        if not self.fast:
            due = self._start_wall + (self.clock() - self._start_sim) / self.speed
            delay = due - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
        return self.stop_requested

    def request_stop(self, *_) -> None:
        self.stop_requested = True


def serve_program(program: str | Path, scene: str | Path | None = None, main: str | None = None,
                  report_path: str | Path | None = None, rrd_path: str | Path | None = None,
                  viewer: bool = False, fast: bool = False, speed: float = 1.0, seed: int | None = None,
                  max_sim_time: float = float("inf"), ports: dict[int, int] | None = None,
                  out: TextIO = sys.stderr) -> RunResult:
    """Run `program` on `scene` until it ends, Ctrl-C, or `max_sim_time`.  `ports` moves
    the program's ports (program port -> real loopback port, 0: any free one)."""
    network.port_map.update(ports or {})
    recorder = None
    if viewer:
        from .recorder import Recorder

        def recorder(sim):  # live: small chunks so that the viewer follows
            return Recorder(sim.cell.model, rrd_path, spawn=True, chunk_frames=15)

    started = start_program(program, scene, main, report_path, rrd_path, seed, recorder=recorder)
    pacer = Pacer(started.simulation.clock, fast, speed, out)
    in_main = threading.current_thread() is threading.main_thread()  # only it may take signals
    previous = {sig: signal.signal(sig, pacer.request_stop) for sig in (signal.SIGINT, signal.SIGTERM)} if in_main else {}
    try:
        outcome = started.simulation.run(max_sim_time=max_sim_time, on_cycle=pacer)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if pacer.stop_requested:
        print("twin serve: stopped", file=out, flush=True)
    return finish_run(started, outcome)
