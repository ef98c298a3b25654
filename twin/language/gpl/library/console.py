"""The global Console class (User Manual ch. 15, Table 15-5): output to the
GPL console, which in the twin is the run's console (stdout and the report)."""

from __future__ import annotations

from ..values import format_value
from . import gpl_class, shared


@gpl_class("Console")
class Console:
    """Numbers and Booleans appear as CStr shows them; WriteLine ends with LF (L2790)."""

    @shared
    def Write(rt, value) -> None:
        rt.console.write(format_value(value))

    @shared
    def WriteLine(rt, value="") -> None:
        rt.console.write(format_value(value) + "\n")
