"""Program control, switches, digital signals, errors, tasks and timers."""

from __future__ import annotations

from .. import messages as msg
from ..values import to_int, truth
from . import function, instruction


@instruction("STOP")
def _stop(rt):
    rt.stop()


@instruction("HALT")
def _halt(rt):
    rt.halt()


@instruction("WAIT", waits=True)
def _wait(rt):
    yield rt.SLICE  # bare WAIT: sleep until the next major cycle


@instruction("SIGNAL")
def _signal(rt, *signals):
    for s in signals:
        if s is not None:
            rt.io.signal(to_int(s))


@instruction("ENABLE", names=True)
def _enable(rt, *names):
    for name in names:
        rt.set_switch(name, True)


@instruction("DISABLE", names=True)
def _disable(rt, *names):
    for name in names:
        rt.set_switch(name, False)




@function("$ERROR")
def _error_text(rt, code):
    return msg.message(to_int(code))


@function("ERROR")
def _error_code(rt, *args):
    return float(rt.last_error or 0)


@function("SIG")
def _sig(rt, *signals):
    return truth(all(rt.io.sig(to_int(s)) for s in signals))


@function("SWITCH")
def _switch(rt, name):
    return truth(rt.switch(name))


@function("TASK")
def _task(rt, *args):
    return float(rt.number)


@function("TIMER")
def _timer(rt, number=0):
    return rt.timer(to_int(number))


@function("SPEED")
def _speed(rt, select=1):
    return rt.robot.speed(to_int(select))
