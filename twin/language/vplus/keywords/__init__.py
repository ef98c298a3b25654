"""The V+ keyword tables: instructions and functions, name -> implementation.

One module per domain (motion, program, numbers, strings, locations, system:
switches, parameters, timers and signals, files: logical-unit I/O); each
registers its keywords with the decorators below when it is imported.

Like the controller's own keyword tables, a name is looked up here when the
program is compiled; an unknown instruction is a load-time error.  An
instruction that may have to wait (a motion, CLOSEI, DELAY...) is a generator
and the compiled program calls it with `yield from`.

Functions take the task (`rt`) first; motion and I/O go through the task's
robot and signal interfaces, which both languages share.
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass
from typing import Callable



@dataclass(frozen=True)
class InstructionSpec:
    function: Callable
    waits: bool = False  # a generator: called with `yield from`
    names: bool = False  # arguments are keyword names (ENABLE CP), not expressions
    # Written by the instruction: READ's items are variables it returns values
    # for; a keyed instruction's array argument (DECOMPOSE a[] = ...) is passed
    # as (array, index).
    targets: bool = False
    returns_unit: bool = False  # ATTACH (lun, 4): the unit number it returns goes into `lun`
    # SOLVE.ANGLES jts[], flags, error = loc, seed[], 0: the values after "=" at these
    # positions are arrays, passed as (array, index), and the plain variables before "="
    # get what the instruction returns at their position (a tuple, None: unchanged).
    array_values: tuple[int, ...] = ()
    # Keyed: the plain variables among the arguments get what the instruction returns at
    # their position.  I/O (READ (lun, handle)): a variable second unit argument gets the
    # last value the instruction returns (None: unchanged).
    writes_back: bool = False
    # WINDOW %b = a, b, program: the values after "=" at these positions are names.
    name_values: tuple[int, ...] = ()


# Argument kinds.  A keyword's parameter is a real unless its annotation says otherwise;
# the compiler checks every argument against its parameter's kind, as the controller's
# keyword table does: a string or a location where a number belongs is *Wrong data type*
# (at load time when the argument is a string constant or a $ expression), never a Python
# error from inside the library.
class Loc:
    """A transformation."""


class Point:
    """A transformation or a precision point (#p): where a motion may go."""


class Str:
    """A string."""


class Any:
    """Anything: the keyword checks it itself (an array, a value of either kind)."""


# kind name (as written in an annotation) -> the check the generated code applies (values.py);
# None, and any other annotation (tuple: an I/O statement's unit and items), checks nothing
_CHECKS = {"Loc": "_location", "Point": "_point", "Str": "_str", "Any": None, "float": "_real"}


def argument_check(fn: Callable, position: int) -> str | None:
    """The check for argument `position` (0 is the first after rt): "_real" unless the
    parameter is annotated with another kind."""
    params = [p for p in list(inspect.signature(fn).parameters.values())[1:] if p.kind is not p.KEYWORD_ONLY]
    if not params:
        return None
    param = params[min(position, len(params) - 1)]
    if position >= len(params) and param.kind is not param.VAR_POSITIONAL:
        return None  # too many arguments: argument_count reports it
    annotation = param.annotation
    if annotation is param.empty:
        return "_real"
    return _CHECKS.get(annotation if isinstance(annotation, str) else annotation.__name__)


INSTRUCTIONS: dict[str, InstructionSpec] = {}
FUNCTIONS: dict[str, Callable] = {}
STRING_FUNCTIONS: dict[str, Callable] = {}


# Functions that also assign to their first argument ($DECODE, TAS): they
# return (result, new value of the first argument).
WRITES_FIRST_ARGUMENT: set[str] = set()
# Functions whose arguments are names, not expressions: PARAMETER(HAND.TIME), SWITCH(CP).
NAME_ARGUMENTS: set[str] = set()


def called_bare(name: str) -> bool:
    """Whether a function keyword can be written without an argument list (PI,
    TRUE, HERE, #PHERE): such a name always means the function, so it cannot
    name a variable.  A function that needs an argument (SIG(n), IOSTAT(lun),
    ERROR(task)) is always followed by "(", and its name may name a variable:
    the manual's own `error = IOSTAT(dlun)` (docs/vplus.md, "Reserved words")."""
    fn = (STRING_FUNCTIONS if name.startswith("$") else FUNCTIONS).get(name)
    if fn is None:
        return False
    return len(inspect.signature(fn).parameters) == 1  # rt alone


def arity(fn: Callable) -> tuple[int, float]:
    """The fewest and most arguments a keyword takes after the task (rt):
    a wrong count is a load-time error, as the controller's editor checks
    each line against its keyword table."""
    fewest, most = 0, 0.0
    for p in list(inspect.signature(fn).parameters.values())[1:]:
        if p.kind is p.VAR_POSITIONAL:
            most = math.inf
        elif p.kind is not p.KEYWORD_ONLY:  # keyword-only: ALWAYS (DURATION t ALWAYS), not an argument
            most += 1
            fewest += p.default is p.empty
    return fewest, most


def instruction(name: str, waits: bool = False, names: bool = False, targets: bool = False,
                returns_unit: bool = False, array_values: tuple[int, ...] = (), writes_back: bool = False,
                name_values: tuple[int, ...] = ()):
    def register(function):
        INSTRUCTIONS[name] = InstructionSpec(function, waits, names, targets, returns_unit,
                                             array_values, writes_back, name_values)
        return function

    return register


def function(name: str, writes_first: bool = False, names: bool = False):
    def register(fn):
        (STRING_FUNCTIONS if name.startswith("$") else FUNCTIONS)[name] = fn
        if writes_first:
            WRITES_FIRST_ARGUMENT.add(name)
        if names:
            NAME_ARGUMENTS.add(name)
        return fn

    return register


# The domain modules register themselves on import (after the registry exists).
from . import absent, belts, files, locations, motion, numbers, program, solve, strings, system, vision  # noqa: E402,F401
