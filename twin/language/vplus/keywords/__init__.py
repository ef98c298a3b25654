"""The V+ keyword tables: instructions and functions, name -> implementation.

One module per domain (motion, program, numbers, strings, locations); each
registers its keywords with the decorators below when it is imported.

Like the controller's own keyword tables, a name is looked up here when the
program is compiled; an unknown instruction is a load-time error.  An
instruction that may have to wait (a motion, CLOSEI, DELAY...) is a generator
and the compiled program calls it with `yield from`.

Functions take the task (`rt`) first; motion and I/O go through the task's
robot and signal interfaces, which both languages share.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable



@dataclass(frozen=True)
class InstructionSpec:
    function: Callable
    waits: bool = False  # a generator: called with `yield from`
    names: bool = False  # arguments are keyword names (ENABLE CP), not expressions


INSTRUCTIONS: dict[str, InstructionSpec] = {}
FUNCTIONS: dict[str, Callable] = {}
STRING_FUNCTIONS: dict[str, Callable] = {}


def instruction(name: str, waits: bool = False, names: bool = False):
    def register(function):
        INSTRUCTIONS[name] = InstructionSpec(function, waits, names)
        return function

    return register


def function(name: str):
    def register(fn):
        (STRING_FUNCTIONS if name.startswith("$") else FUNCTIONS)[name] = fn
        return fn

    return register


# The domain modules register themselves on import (after the registry exists).
from . import locations, motion, numbers, program, strings  # noqa: E402,F401
