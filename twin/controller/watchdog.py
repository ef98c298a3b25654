"""The runaway watchdog: a run that can no longer get anywhere is stopped and explained.

Three rules, checked once per major cycle (docs/robustness.md, "Runaways"):

* **Deadlock**: nothing can change any more.  Every live task is blocked on a
  condition (a V+ WAIT, WAIT.EVENT without a timeout, a GPL Join, WaitEvent,
  a signal wait...), no task read the clock while it waited (a time-out or a
  TIMER() test will end the wait) or waits with a deadline of its own (`timed`:
  the servos' nulling time-out), the robot has no motion queued, and the
  cell is at rest (no signal changed, no cell event, no body moving, no
  encoder counting, no part source that will bring a part).  The state is
  then a fixed point of the whole simulation: each later cycle is the same as
  this one.  It is confirmed over `deadlock_confirm_s` of simulated time (1 s
  plus the longest feeder delay) so that a part just coming to rest or about
  to be presented is not mistaken for it.
* **No progress**: for `no_progress_s` simulated seconds nothing the programs
  do or look at changed: the robot's joints did not move, the hand was not
  driven, no output or soft signal changed, no input that a program has read
  changed, no task started or ended.  A program spinning in a loop, however
  much it computes, prints or writes to its own files, is stopped, even in a
  cell whose belts carry parts past it; a program polling a sensor is not
  while the parts it waits for keep arriving (its input changes).  A task
  waiting on the outside world (a socket accept or receive, a V+ network
  read) holds the clock: a peer may connect at any time.
* **Wall time**: `max_wall_s` seconds of real time (nondeterministic by nature,
  so off unless asked for).

Each rule answers a ProgramError whose message names every live task, its
program, line and what it is doing there.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable

from ..errors import ProgramError
from .scheduler import NEXT_CYCLE, RELEASE

DEFAULT_NO_PROGRESS_S = 30.0
DEADLOCK_CONFIRM_S = 1.0
# Twin-defined codes (the controllers have no watchdog of this kind): docs/robustness.md.
DEADLOCK = -1030
NO_PROGRESS = -1031
WALL_TIME_LIMIT = -1032


def external(condition: Callable[[], bool]) -> Callable[[], bool]:
    """Mark a wait condition as driven from outside the twin (a socket): the watchdog never
    takes a task blocked on it for a deadlock, and the no-progress clock waits with it."""
    condition.external = True  # type: ignore[attr-defined]
    return condition


def timed(condition: Callable[[], bool]) -> Callable[[], bool]:
    """Mark a wait condition that ends by itself at a deadline of simulated time (the servos'
    nulling time-out): a task waiting on it is not blocked for good, so the wait ends with
    its own error, not a deadlock."""
    condition.timed = True  # type: ignore[attr-defined]
    return condition


@dataclass(frozen=True)
class WatchdogLimits:
    no_progress_s: float | None = DEFAULT_NO_PROGRESS_S  # None: no such limit
    max_wall_s: float | None = None
    deadlock_confirm_s: float = DEADLOCK_CONFIRM_S  # how long a fixed point must last


class Watchdog:
    """Told once per major cycle what happened; answers the error that ends the run, if any."""

    def __init__(self, limits: WatchdogLimits, wall_clock: Callable[[], float] = time.perf_counter):
        self.limits = limits
        self._wall_clock = wall_clock
        self._wall_start = wall_clock()
        self._last_progress_t = 0.0
        self._blocked_since: float | None = None

    def observe(self, t: float, progressed: bool, blocked: bool, external_wait: bool,
                tasks: Iterable[Any]) -> ProgramError | None:
        """`progressed`: something visible changed this cycle; `blocked`: every task is blocked
        and nothing can unblock it (see the module docstring); `external_wait`: a task waits on
        the outside world."""
        if progressed or external_wait:
            self._last_progress_t = t
        if blocked and not progressed:
            if self._blocked_since is None:
                self._blocked_since = t
            elif t - self._blocked_since >= self.limits.deadlock_confirm_s - 1e-9:
                return self._error(DEADLOCK, "*Deadlock* nothing can change any more: every task waits "
                                   "for something no task, signal or part will bring", tasks)
        else:
            self._blocked_since = None
        limit = self.limits.no_progress_s
        if limit is not None and t - self._last_progress_t >= limit - 1e-9:
            return self._error(NO_PROGRESS, f"*No progress* for {limit:g} s of simulated time: no robot or "
                               "hand motion, no output changed, no input the program reads changed (limit: "
                               "[controller] no_progress_s or --no-progress-limit)", tasks)
        wall = self.limits.max_wall_s
        if wall is not None and self._wall_clock() - self._wall_start >= wall:
            return self._error(WALL_TIME_LIMIT, f"*Wall time limit reached* ({wall:g} s)", tasks)
        return None

    @staticmethod
    def _error(code: int, message: str, tasks: Iterable[Any]) -> ProgramError:
        lines = [describe_task(task) for task in tasks]
        text = "\n".join(line for line in lines if line) or None
        return ProgramError(message, code, text=text)


def describe_task(task: Any) -> str:
    """'task 0 (move.parts) at move.parts step 4, line 7: WAIT SIG(1001)': a task's name, program,
    line and the statement it is at (what it waits for), as far as the task can tell."""
    name = getattr(task, "label", None) or type(task).__name__
    where = getattr(task, "current_location", None)
    location = where() if where is not None else None
    if not location:
        return f"{name}: running"
    parts = [f"{name} in {location['program']}"]
    if location.get("step") is not None:
        parts.append(f"step {location['step']}")
    if location.get("file"):
        parts.append(f"{location['file']}:{location['line']}")
    text = (location.get("text") or "").strip()
    return ", ".join(parts) + (f": {text}" if text else "")


def task_is_blocked(wait: Any, slice_token: Any) -> bool:
    """A task whose last yield was a wait condition (not a `timed` one), a V+ WAIT's release
    or a bare WAIT (not a used-up time slice: that one is computing)."""
    if wait is None or wait is slice_token or getattr(wait, "timed", False):
        return False
    return wait is RELEASE or wait is NEXT_CYCLE or callable(wait)


def is_external(wait: Any) -> bool:
    return bool(getattr(wait, "external", False))
