"""Run GPL source text on the interpreter alone (no cell), for language tests."""

from __future__ import annotations

import io

from twin.controller.io import DigitalIO
from twin.controller.scheduler import Scheduler
from twin.language.gpl.runtime import GplSystem
from twin.language.vplus.runtime import MAJOR_CYCLE, Console


# The lock routines of ch. 18 "Creating Thread-Safe Interlocks" (L3351-3367), whose
# bodies the manual lost, written with Thread.TestAndSet; GPL module members.
SEMAPHORES = """    Public Sub acquire_sem(ByRef lock As Integer)
        While Thread.TestAndSet(lock, 1) <> 0
            Thread.Sleep(0)
        End While
    End Sub
    Public Sub release_sem(ByRef lock As Integer)
        lock = 0
    End Sub
"""


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
    return _run(lambda system: system.load_text(text, "test.gpl"), start, max_cycles, robot or NoRobot(), sandbox)


def _run(load, start, max_cycles: int, robot, sandbox):
    clock = Clock()
    scheduler = Scheduler()
    console = Console(stdin=io.StringIO(""), echo=None)
    system = GplSystem(robot, DigitalIO(), clock, scheduler, console, sandbox=sandbox)
    load(system)
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


def main_project(tmp_path, body: str, declarations: str = ""):
    """A project folder `tmp_path/proj`: Module Test with `declarations`, then Public Sub
    Main() with `body` (its first line is line 3 when there are no declarations)."""
    folder = tmp_path / "proj"
    folder.mkdir()
    (folder / "Project.gpr").write_text(
        'ProjectBegin\nProjectName="proj"\nProjectStart="Main"\nProjectSource="Main.gpl"\nProjectEnd\n')
    (folder / "Main.gpl").write_text(
        "Module Test\n" + declarations + "    Public Sub Main()\n" + body + "    End Sub\nEnd Module\n")
    return folder


def run_project(folder, max_cycles: int = 100000, sandbox=None):
    """Load a project folder (Project.gpr), run its start procedure and threads to
    the end without a cell; returns (system, main thread)."""
    return _run(lambda system: system.load_project(folder), None, max_cycles, NoRobot(), sandbox)
