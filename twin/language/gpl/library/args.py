"""Arguments of built-in members converted as GPL converts values (User Manual ch. 4,
"automatically converts one type of variable to another as needed"): a number, a
Boolean or a numeric String is accepted where a number is expected; anything else
is the GPL error the interpreter gives for that conversion (-708 for a String that
is not a number, -2004 for an object), which the program's Try/Catch can catch."""

from __future__ import annotations

from numbers import Real

from .. import values


def number(value) -> float:
    """A Double argument."""
    if isinstance(value, Real) and not isinstance(value, bool):
        return float(value)
    return values._cdbl(value)


def integer(value) -> int:
    """An Integer argument (a real is rounded, as on assignment to an Integer)."""
    if isinstance(value, Real) and not isinstance(value, (bool, float)):
        return values._cint(int(value))
    return values._cint(value)


def text(value) -> str:
    """A String argument (a number is shown as CStr shows it)."""
    return values._cstr(value)


def flag(value) -> bool:
    """A Boolean argument."""
    return values._cbool(value)
