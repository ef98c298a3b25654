"""The GPL built-in classes (Signal, Location, Profile, Move, Thread, ...).

The contract between the interpreter and the library:

* A built-in class is a Python class registered with ``@gpl_class("Name")``.
  ``CLASSES`` maps the lower-cased GPL name to the class; GPL names are
  case-insensitive, so the interpreter looks members up with ``member(cls, name)``.
* ``New Name(args)`` calls ``cls(rt, *args)``: constructors take the runtime first.
* Instance methods are plain methods ``fn(self, *args)``; instance properties are
  Python ``property`` objects (getter, and setter when writable).
* Shared (static) members are marked ``@shared`` and called as ``fn(rt, *args)``
  (a shared property is a ``@shared`` function ``Name(rt)``; when assignable, its
  setter is the ``@shared`` function ``set_Name(rt, value)``).
* A member that must wait for simulated time (Move.WaitForEOM, Thread.Sleep,
  Thread.Join...) is a generator function: the interpreter runs it with
  ``yield from``; it yields what scheduler predicates yield (see
  twin/controller/scheduler.py).
* Errors are raised as ``GplError(code, message)`` (twin/language/gpl/errors.py).
* GPL values in Python: Integer/Short/Byte ``int``, Double and Single
  ``float``, Boolean ``bool``, String ``str``, Nothing ``None``, arrays
  ``twin.language.gpl.values.GplArray``.
* Indexed properties (``loc.Angle(n)``, ``Signal.DIO(n)``, ``Controller.PDb(id)``)
  are methods: reading ``x.Name(i)`` calls ``Name(i)``; assigning
  ``x.Name(i) = v`` calls ``set_Name(i, v)`` (shared: ``set_Name(rt, i, v)``).
* ByRef parameters of built-in members (``Socket.Receive(ByRef buf, n)``,
  ``Modbus.ReadCoils(start, n, ByRef bits)``, ``Thread.TestAndSet(ByRef v, new)``,
  ``Controller.ShowDialog(buttons, msg, ByRef button)``) are declared with
  ``@byref(i, ...)`` (0-based argument positions, not counting self / rt).  There
  the interpreter passes a ``Ref``: an object whose ``value`` attribute reads and
  writes the caller's variable (``Ref`` below: written back when the member
  returns; put ``@byref`` above ``@shared``).
* ``rt.current_thread()`` is the handle of the calling thread (who has the
  robot attached, Thread.CurrentThread).

``rt`` (GplRuntime below) is what a running GPL project offers the library.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Protocol

CLASSES: dict[str, type] = {}


class GplRuntime(Protocol):
    robot: Any  # twin.controller.controller.VirtualController (shared with V+)
    io: Any  # twin.controller.io.DigitalIO
    console: Any  # .write(text): the GPL console output
    sandbox: Path  # folder that file I/O is confined to

    def clock(self) -> float: ...  # simulated seconds

    def current_thread(self) -> Any: ...

    def start_thread(self, delegate: Any, name: str) -> Any: ...
    # Run a GPL procedure (a delegate / AddressOf, or its name as a String:
    # "proc", "module.proc", "class.proc") as a new cooperative thread; returns
    # a handle with `.alive` (bool), `.error` (None, or the ProgramError that
    # stopped it: `.code`, `.message`, located in the source), `.name`,
    # `.procedure`, and `abort()`, `suspend()`, `resume()`.


def gpl_class(name: str) -> Callable[[type], type]:
    def register(cls: type) -> type:
        cls.gpl_name = name
        # A GPL member (capitalised: Angles) wins over a Python helper of the same name
        # in another case (the classmethod angles that builds an Angles location).
        cls.gpl_members = {
            attr.lower(): attr for attr in sorted(dir(cls), key=lambda a: a[:1].isupper()) if not attr.startswith("_")
        }
        CLASSES[name.lower()] = cls
        return cls

    return register


def shared(fn: Callable) -> staticmethod:
    """Mark a shared (static) member: called as fn(rt, *args)."""
    fn.gpl_shared = True
    return staticmethod(fn)


class Ref:
    """A ByRef argument: the built-in reads and assigns `value`; the interpreter
    writes `value` back to the caller's variable when the member returns."""

    __slots__ = ("value",)

    def __init__(self, value: Any = None):
        self.value = value


def byref(*positions: int) -> Callable[[Callable], Callable]:
    """Mark the 0-based argument positions that are ByRef (they receive a Ref)."""

    def mark(fn: Callable) -> Callable:
        target = fn.__func__ if isinstance(fn, staticmethod) else fn
        target.gpl_byref = frozenset(positions)
        return fn

    return mark


def member(cls: type, name: str) -> str | None:
    """The Python attribute behind GPL member `name` (any case), or None."""
    return cls.gpl_members.get(name.lower())


# The classes register themselves on import.
from . import console, conveyor, files, locations, modbus, motion, net, robot, signal, thread, vision, xmldoc  # noqa: E402,F401
