"""Run V+ program text on the interpreter alone (no cell), for language tests."""

from __future__ import annotations

import io

from twin.controller.io import DigitalIO
from twin.controller.scheduler import Scheduler
from twin.language.vplus.runtime import MAJOR_CYCLE, Console, VPlusSystem


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def run_vplus(text: str, main: str | None = None, stdin: str = "", max_cycles: int = 100000,
              sandbox=None, setup=None, each_cycle=None, robot=None):
    """Load `text`, run its first (or `main`) program until no task is left
    running; return (system, task of the main program).
    `sandbox` is the disk folder; `setup(system)` runs before the program starts
    (to feed serial lines, set signals...); `each_cycle(system)` runs before
    every major cycle (to drive inputs on simulated time)."""
    clock = Clock()
    console = Console(stdin=io.StringIO(stdin), echo=None)
    system = VPlusSystem(robot=robot, io=DigitalIO(), clock=clock, console=console, sandbox=sandbox)
    if setup is not None:
        setup(system)
    names = system.load_text(text, "test.pg")
    task = system.start(main or names[0])
    scheduler = Scheduler()
    scheduler.add(task)
    for _ in range(max_cycles):
        if not scheduler.alive:
            break
        if each_cycle is not None:
            each_cycle(system)
        scheduler.run_cycle()
        clock.t += MAJOR_CYCLE
    return system, task


def output_of(text: str, **kw) -> str:
    system, task = run_vplus(text, **kw)
    if task.error is not None:
        raise task.error
    return system.console.output
