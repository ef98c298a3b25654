"""The global Console class (User Manual ch. 15, Table 15-5): output to the
GPL console, which in the twin is the run's console (stdout and the report)."""

from __future__ import annotations

from . import gpl_class, shared


def text_of(value) -> str:
    """A number, Boolean or String as Console.Write shows it: integers without a
    decimal point, other numbers with up to 15 significant digits, Booleans as
    True / False (VB.NET's forms; the manual does not say, digest §15 item 7)."""
    if isinstance(value, bool):
        return "True" if value else "False"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if value.is_integer() and abs(value) < 1e15:
            return str(int(value))
        return f"{value:.15g}"
    return str(value)


@gpl_class("Console")
class Console:
    @shared
    def Write(rt, value) -> None:
        rt.console.write(text_of(value))

    @shared
    def WriteLine(rt, value="") -> None:
        rt.console.write(text_of(value) + "\n")
