"""Program control and errors: STOP, HALT, ERROR, $ERROR, SPEED().

WAIT and TASK() are compiled by the compiler itself (compiler.py, tasking.py)."""

from __future__ import annotations

from .. import messages as msg
from ..values import to_int
from . import function, instruction


@instruction("STOP")
def _stop(rt):
    rt.stop()


@instruction("HALT")
def _halt(rt):
    rt.halt()


@function("$ERROR")
def _error_text(rt, code):
    """$ERROR(code): the controller's message for an error code."""
    return msg.message(to_int(code))


@function("ERROR")
def _error_code(rt, source=None, select=None):
    """ERROR(task): the code of the latest error of a task (this one when the
    task is omitted or -1), 0 if it has had none."""
    number = rt.number if source is None or to_int(source) < 0 else to_int(source)
    for task in [rt, *rt.system.tasks]:
        if task.number == number:
            return float(task.last_error or 0)
    return 0.0


@function("SPEED")
def _speed(rt, select=1):
    return rt.robot.speed(to_int(select))
