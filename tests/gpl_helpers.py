"""Run GPL source text on the interpreter alone (no cell), for language tests."""

from __future__ import annotations

import io

from twin.controller.io import DigitalIO
from twin.controller.scheduler import Scheduler
from twin.language.gpl.runtime import GplSystem
from twin.language.vplus.runtime import MAJOR_CYCLE, Console


class NoRobot:
    """A run without a cell has no controller; the library keeps its per-robot
    state (threads' events, power) keyed on this object instead."""


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def run_gpl(text: str, start: str = "Main", max_cycles: int = 100000, robot=None, sandbox=None):
    """Load `text` (one file, any number of modules), run `start` and every thread
    it starts to the end; returns (system, main thread)."""
    clock = Clock()
    scheduler = Scheduler()
    console = Console(stdin=io.StringIO(""), echo=None)
    system = GplSystem(robot or NoRobot(), DigitalIO(), clock, scheduler, console, sandbox=sandbox)
    system.load_text(text, "test.gpl")
    thread = system.start(start)
    for _ in range(max_cycles):
        if not scheduler.alive:
            break
        scheduler.run_cycle()
        clock.t += MAJOR_CYCLE
    return system, thread


def output_of(text: str, **kw) -> str:
    """The console output of a run that must end without an error."""
    system, thread = run_gpl(text, **kw)
    errors = [t.error for t in system.threads if t.error is not None]
    if errors:
        raise errors[0]
    return system.console.output


def error_of(text: str, **kw):
    """The error that stopped the main thread (a ProgramError)."""
    system, thread = run_gpl(text, **kw)
    assert thread.error is not None, "expected the program to stop on an error"
    return thread.error
