"""The Thread class (User Manual ch. 18, L3246-3391) on the shared cooperative
scheduler: GPL threads are scheduler tasks like V+ tasks, and every wait is in
simulated time.

Decisions (docs/gpl.md):
* ``New Thread(procedure[, project[, name]])``: `procedure` is the start
  procedure's name (a String, "Proc", "Module.Proc" or "Class.Proc") or a
  delegate; the interpreter resolves it when the thread starts.
* ``Thread.Sleep(ms)``: milliseconds of simulated time; the thread resumes at
  the first scheduler cycle at or after the end (cycles are 16 ms); ``Sleep(0)``
  gives up the rest of the cycle.  A negative time is an error.
* Events: 16 per thread, bit n-1 = event n; ``WaitEvent(mask, timeout)``:
  timeout 0 polls, < 0 waits forever, > 0 waits up to that many ms; returns the
  received events of the mask (0 on timeout) and clears them.
* ``Thread.Schedule`` (priorities) is accepted and recorded: the twin's
  scheduler runs every ready thread once per cycle, in start order.
* ThreadState: -1 never started, 0 finished, 2 running, 3 suspended.
"""

from __future__ import annotations

from . import codes
from . import byref, gpl_class, shared
from .members import stored
from .state import robot_state

FOREVER = -1
ALL_EVENTS = 0xFFFF
THREAD_NONE, THREAD_IDLE, THREAD_RUNNING, THREAD_SUSPENDED = -1, 0, 2, 3


def _events(rt) -> dict:
    """Pending event masks by thread handle."""
    return robot_state(rt).events


def _objects(rt) -> dict:
    """The Thread object of each handle, so CurrentThread returns the same object."""
    return robot_state(rt).threads


def wait_ms(rt, ms: float, until=None):
    """Wait `ms` of simulated time (< 0: forever), or until `until()` is true."""
    clock = rt.clock
    end = None if ms < 0 else clock() + ms / 1000.0
    start = clock()

    def ready() -> bool:
        if until is not None and until():
            return True
        if end is None:
            return False
        return clock() >= end - 1e-9 and clock() > start

    ready.external = getattr(until, "external", False)  # a socket: the watchdog leaves it be
    yield ready


@gpl_class("Thread")
class GplThread:
    """A GPL Thread object."""

    def __init__(self, rt, procedure=None, project="", name="", stack=0):
        if procedure is None:
            raise codes.fail(codes.NOTHING_ARGUMENT, "New Thread needs a procedure")
        self._rt = rt
        self._procedure = procedure
        self._project = str(project)
        self._name = str(name) if name else _procedure_name(procedure)
        self._handle = None
        self._argument = 0.0
        self.priority = None

    @classmethod
    def of_handle(cls, rt, handle) -> "GplThread":
        thread = cls.__new__(cls)
        thread._rt = rt
        thread._procedure = getattr(handle, "procedure", "")
        thread._project = ""
        thread._name = str(getattr(handle, "name", "main"))
        thread._handle = handle
        thread._argument = 0.0
        thread.priority = None
        return thread

    # ------------------------------------------------------------ properties
    @property
    def Name(self) -> str:
        return self._name

    @property
    def Project(self) -> str:
        return self._project

    @property
    def StartProcedure(self) -> str:
        return _procedure_name(self._procedure)

    Argument = stored("_argument", float)

    @property
    def ThreadState(self) -> int:
        handle = self._handle
        if handle is None:
            return THREAD_NONE
        if not handle.alive:
            return THREAD_IDLE
        return THREAD_SUSPENDED if getattr(handle, "suspended", False) else THREAD_RUNNING

    # ------------------------------------------------------------ control
    def Start(self) -> None:
        """Start the procedure as a new thread; nothing happens while it is running."""
        if self._handle is not None and self._handle.alive:
            return
        self._handle = self._rt.start_thread(self._procedure, self._name)
        _objects(self._rt)[self._handle] = self

    def Join(self, timeout_ms=FOREVER):
        """Wait for the thread to end: True when it has ended, False on timeout."""
        handle = self._handle
        if handle is None or not handle.alive:
            return True
        timeout = float(timeout_ms)
        if timeout != 0:
            yield from wait_ms(self._rt, timeout, until=lambda: not handle.alive)
        return not handle.alive

    def _control(self, action: str) -> None:
        if self._handle is None:
            raise codes.fail(codes.THREAD_ERROR, f"{action}: the thread was never started")
        method = getattr(self._handle, action, None)
        if method is None:
            raise codes.fail(codes.NOT_SUPPORTED, f"Thread.{action.capitalize()}")
        method()

    def Abort(self) -> None:
        self._control("abort")

    def Suspend(self) -> None:
        self._control("suspend")

    def Resume(self) -> None:
        self._control("resume")

    def SendEvent(self, mask) -> None:
        if self._handle is None:
            raise codes.fail(codes.THREAD_ERROR, "SendEvent: the thread was never started")
        events = _events(self._rt)
        events[self._handle] = events.get(self._handle, 0) | (int(mask) & ALL_EVENTS)

    # ------------------------------------------------------------ shared members
    @shared
    def CurrentThread(rt) -> "GplThread":
        handle = rt.current_thread()
        objects = _objects(rt)
        if handle not in objects:
            objects[handle] = GplThread.of_handle(rt, handle)
        return objects[handle]

    @shared
    def Sleep(rt, ms):
        ms = float(ms)
        if ms < 0:
            raise codes.fail(codes.INVALID_ARGUMENT, f"Thread.Sleep({ms:g})")
        yield from wait_ms(rt, ms)

    @byref(0)
    @shared
    def TestAndSet(rt, variable, new_value):
        """Read the variable and write the new value in one step (threads only switch
        at waits in the twin, so this is atomic); returns the old value."""
        old = variable.value
        variable.value = new_value
        return old

    @shared
    def WaitEvent(rt, mask, timeout_ms=FOREVER):
        me = rt.current_thread()
        events = _events(rt)
        mask = int(mask) & ALL_EVENTS or ALL_EVENTS

        def received() -> int:
            return events.get(me, 0) & mask

        timeout = float(timeout_ms)
        if not received() and timeout != 0:
            yield from wait_ms(rt, timeout, until=lambda: received() != 0)
        got = received()
        events[me] = events.get(me, 0) & ~got
        return got

    @shared
    def Schedule(rt, *args) -> None:
        """Accepted and recorded on the current thread's object; see the module docstring."""
        GplThread.CurrentThread(rt).priority = args


def _procedure_name(procedure) -> str:
    return procedure if isinstance(procedure, str) else str(getattr(procedure, "name", procedure))
