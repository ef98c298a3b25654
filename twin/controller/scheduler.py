"""Cooperative tasks on simulated time, shared by V+ tasks and GPL threads.

A task is a generator.  It runs until it yields a *wait*: either a callable
that returns True once the task may go on (a motion has finished, a time has
come, a signal is on), or the task's SLICE token, which means "my time slice
is used up, resume me next cycle".  `run_cycle()` is called once per major
cycle (16 ms on V+), between physics steps, so nothing in a program ever
waits on the wall clock.
"""

from __future__ import annotations

from typing import Any, Iterator, Protocol


class Runnable(Protocol):
    generator: Iterator[Any]
    finished: bool
    SLICE: Any


class Scheduler:
    def __init__(self) -> None:
        self.tasks: list[Runnable] = []
        self._waits: dict[int, Any] = {}

    def add(self, task: Runnable) -> None:
        self.tasks.append(task)

    @property
    def alive(self) -> bool:
        return any(not t.finished for t in self.tasks)

    def run_cycle(self) -> None:
        """Give every ready task its turn in this cycle."""
        for task in self.tasks:
            if task.finished:
                continue
            wait = self._waits.get(id(task))
            if wait is not None and wait is not task.SLICE and not wait():
                continue
            self._resume(task)

    def _resume(self, task: Runnable) -> None:
        while True:
            try:
                wait = next(task.generator)
            except StopIteration:
                task.finished = True
                self._waits.pop(id(task), None)
                return
            if wait is task.SLICE:
                self._waits[id(task)] = wait
                return
            if callable(wait) and wait():
                continue  # already satisfied: no reason to lose the cycle
            self._waits[id(task)] = wait
            return

