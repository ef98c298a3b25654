"""Cooperative tasks on simulated time, shared by V+ tasks and GPL threads.

A task is a generator.  It runs until it yields a *wait*: a callable that
returns True once the task may go on (a motion has finished, a time has come,
a signal is on), or one of the tokens below.  `run_cycle()` is called once per
major cycle (16 ms on V+), between physics steps, so nothing in a program ever
waits on the wall clock.

The cycle is split the way the V+ scheduler splits it (V+ guide v17,
"Scheduling of Program Execution Tasks"): 16 time slices of 1 ms.  In each
slice the ready task with the highest priority *for that slice* runs; equal
priorities form a round-robin group in which the task that ran least recently
goes first; priority 0 runs only when no other task of the slice is ready and
-1 never.  A task keeps the CPU until it waits, releases it, or yields its
SLICE token (its 1 ms is used up: compiled loops yield it every so many
passes); when it waits or releases, the search goes on in the same slice.
"""

from __future__ import annotations

from typing import Any, Iterator, Protocol

SLICES = 16  # time slices per major cycle
# A task that brings no table of its own (a GPL thread: GPL has no slice
# table) runs in slice 0 only: one turn per major cycle.
DEFAULT_PRIORITIES = (10,) + (-1,) * (SLICES - 1)


class _Token:
    def __init__(self, name: str) -> None:
        self.name = name

    def __repr__(self) -> str:
        return self.name


# RELEASE: let the other ready tasks run; ready again from the next slice on
# (V+ RELEASE, and what WAIT does while its condition is false).
RELEASE = _Token("RELEASE")
# NEXT_CYCLE: sleep until slice 0 of the next major cycle (V+ bare WAIT).
NEXT_CYCLE = _Token("NEXT_CYCLE")
# NETWORK_CYCLE: NEXT_CYCLE for a task polling the network: what it waits for comes from
# outside the twin, so the watchdog never takes it for a deadlock (watchdog.external).
NETWORK_CYCLE = _Token("NETWORK_CYCLE")
NETWORK_CYCLE.external = True
_NEXT_CYCLE = (NEXT_CYCLE, NETWORK_CYCLE)


class Runnable(Protocol):
    """What the scheduler needs of a task.  Optional, read with getattr:
    `priorities` (16 slice priorities), `paused` (not run, and not counted as
    alive), `begin_cycle()` (called at the start of each major cycle),
    `interrupt_due()` (True: resume even though the wait is not over, to run
    a reaction) and `scheduler` (set by `add`)."""

    generator: Iterator[Any]
    finished: bool
    SLICE: Any


class Scheduler:
    def __init__(self) -> None:
        self.tasks: list[Runnable] = []
        self._waits: dict[int, Any] = {}
        self._last_run: dict[int, int] = {}
        self._runs = 0
        # A wait's answer only changes when some task has run (time and the
        # cell stand still inside a cycle): (runs, answer) per task.
        self._answers: dict[int, tuple[int, bool]] = {}

    def add(self, task: Runnable) -> None:
        """Add a task; one with a `scheduler` attribute learns its scheduler,
        so that it can start others (V+ EXECUTE)."""
        if hasattr(task, "scheduler"):
            task.scheduler = self
        self.tasks.append(task)

    def waiting_on(self, task: Runnable) -> Any:
        """What `task` last yielded: a wait condition, a token, or None (not waiting)."""
        return self._waits.get(id(task))

    @property
    def runs(self) -> int:
        """How many times a task has been resumed: where the tasks are (and what they did)
        changes only when this grows."""
        return self._runs

    @property
    def alive(self) -> bool:
        return any(not t.finished and not getattr(t, "paused", False) for t in self.tasks)

    def run_cycle(self) -> None:
        """One major cycle: every slice gives the CPU to the ready tasks in priority order."""
        self._answers.clear()  # time has moved on
        for task in self.tasks:
            begin = getattr(task, "begin_cycle", None)
            if begin is not None and not task.finished:
                begin()
            if self._waits.get(id(task)) in _NEXT_CYCLE:
                del self._waits[id(task)]
        for slice_number in range(SLICES):
            passed: set[int] = set()
            while True:
                task = self._select(slice_number, passed)
                if task is None:
                    break
                if self._resume(task):
                    break  # the task used up the slice
                passed.add(id(task))
            if not any(self._ready(t) for t in self.tasks):
                break  # every task waits: nothing can change before the next cycle

    def _ready(self, task: Runnable) -> bool:
        if task.finished or getattr(task, "paused", False):
            return False
        wait = self._waits.get(id(task))
        if wait is None or wait is task.SLICE or wait is RELEASE:
            return True
        known = self._answers.get(id(task))
        if known is not None and known[0] == self._runs:
            return known[1]
        interrupt = getattr(task, "interrupt_due", None)
        answer = (interrupt is not None and interrupt()) or (wait not in _NEXT_CYCLE and wait())
        self._answers[id(task)] = (self._runs, answer)
        return answer

    def _select(self, slice_number: int, passed: set[int]) -> Runnable | None:
        best, best_key = None, None
        for task in self.tasks:
            if id(task) in passed:
                continue
            priority = getattr(task, "priorities", DEFAULT_PRIORITIES)[slice_number]
            if priority < 0 or not self._ready(task):
                continue
            key = (priority, -self._last_run.get(id(task), -1))
            if best_key is None or key > best_key:
                best, best_key = task, key
        return best

    def _resume(self, task: Runnable) -> bool:
        """Run `task` until it waits; True when it used up its time slice."""
        self._runs += 1
        self._last_run[id(task)] = self._runs
        while True:
            try:
                wait = next(task.generator)
            except StopIteration:
                task.finished = True
                self._waits.pop(id(task), None)
                return False
            if callable(wait) and wait():
                continue  # already satisfied: no reason to lose the slice
            self._waits[id(task)] = wait
            return wait is task.SLICE
