"""Switches, parameters, timers, digital signals and system information
(V+ guide v17, "System Control Functions", "Digital I/O", "System Switches",
"System Parameters"; eV+ guide, same tables).

Signals are numbered as on the controller: outputs 1-512, inputs 1001-1512,
soft signals 2001-2512 and 3001-3004 (controller/io.py); a negative number means "off".
"""

from __future__ import annotations

from datetime import datetime, timedelta

from ....controller import io as dio
from .. import messages as msg
from ..values import FALSE, TRUE, VArray, fail, to_int, truth
from . import Any, function, instruction

TICKS_PER_SECOND = 1000.0  # TPS: the scheduler's 1 ms time slice
SYSTEM_ID = "twin V+ emulation"  # $ID: the guides give no layout
CALENDAR_START = datetime(2000, 1, 1)  # what $TIME shows at simulated time 0


# ---- device selection: the cell has one robot, unit 1
ROBOT_UNITS = 1


def _robot_device(device: str) -> None:
    if device != "ROBOT":  # VISION, BELT... select hardware the twin does not have
        raise fail(msg.DEVICE_NOT_READY, f"SELECT {device}")


@instruction("SELECT", names=True)
def _select(rt, unit, device):
    """SELECT ROBOT = n: the robot the task's motion keywords drive ([000] L7020)."""
    _robot_device(device)
    if not 1 <= to_int(unit) <= ROBOT_UNITS:
        raise fail(msg.ILLEGAL_VALUE, f"robot {to_int(unit)}: the cell has {ROBOT_UNITS}")


@function("SELECT", names=True)
def _selected(rt, device):
    """SELECT(ROBOT): the unit the task has selected ([000] L5539, L7023)."""
    _robot_device(device)
    return 1.0


# ---- switches and parameters
@instruction("ENABLE", names=True)
def _enable(rt, *names):
    for name in names:
        rt.set_switch(name, True)


@instruction("DISABLE", names=True)
def _disable(rt, *names):
    for name in names:
        rt.set_switch(name, False)


@instruction("SWITCH", names=True)
def _set_switch(rt, value, name, index=None):
    """SWITCH name = value: enable when the value is nonzero."""
    rt.set_switch(name, bool(value))


@function("SWITCH", names=True)
def _switch(rt, name, index=None):
    return truth(rt.switch(name))


@function("PARAMETER", names=True)
def _parameter(rt, name, index=None):
    from ..runtime import _pick  # the same unique-prefix rule as PARAMETER name = value

    return rt.system.parameters[_pick(rt.system.parameters, name)]


# ---- timers
@instruction("TIMER")
def _set_timer(rt, value, number):
    """TIMER n = value: timer n reads `value` now and counts up in seconds."""
    rt.system.timers[to_int(number)] = rt.system.clock() - float(value)


@function("TIMER")
def _timer(rt, number=0):
    """TIMER(n): seconds on timer n; a timer never set counts from system start."""
    return rt.system.clock() - rt.system.timers.get(to_int(number), 0.0)


@function("TPS")
def _tps(rt):
    return TICKS_PER_SECOND


@function("$TIME")
def _time_text(rt, *args: Any):
    """$TIME(): the simulated date and time, "dd-MMM-yy hh:mm:ss".  The calendar
    starts at 01-JAN-00 00:00:00 when the run starts, so runs are repeatable."""
    if args:
        raise fail(msg.INVALID_ARGUMENT, "$TIME(date, time) is not supported")
    moment = CALENDAR_START + timedelta(seconds=int(rt.system.clock()))
    return moment.strftime("%d-%b-%y %H:%M:%S").upper()


# ---- digital signals
@instruction("SIGNAL")
def _signal(rt, *signals):
    for s in signals:
        if s is not None:
            rt.io.signal(to_int(s))


@function("SIG")
def _sig(rt, *signals):
    """SIG(s, ...): true when every signal is in the state its sign asks for."""
    return truth(all(rt.io.sig(to_int(s)) for s in signals))


@function("SIG.INS")
def _sig_ins(rt, signal):
    number = abs(to_int(signal))
    return TRUE if number in dio.OUTPUTS or number in dio.INPUTS or number in dio.SOFT else FALSE


def _group(first, count) -> range:
    first, count = to_int(first), to_int(count)
    if not 1 <= count <= 32:
        raise fail(msg.ILLEGAL_VALUE, f"BITS count {count}")
    return range(first, first + count)


@function("BITS")
def _bits(rt, first, count=1):
    """BITS(first, count): the signals as a binary number, `first` the lowest bit."""
    return float(sum(1 << i for i, s in enumerate(_group(first, count)) if rt.io.sig(s)))


@instruction("BITS")
def _set_bits(rt, value, first, count=1):
    """BITS first, count = value: set the signals to the value's low bits."""
    bits = to_int(value)
    for i, s in enumerate(_group(first, count)):
        rt.io.signal(s if bits >> i & 1 else -s)


@instruction("RESET")
def _reset(rt):
    """RESET: every digital output off."""
    for number in dio.OUTPUTS:
        if rt.io.sig(number):
            rt.io.signal(-number)


# ---- memory, interlocks, identity
@function("LAST")
def _last(rt, array: Any):
    if not isinstance(array, VArray):
        raise fail(msg.WRONG_TYPE, "LAST needs an array, a[]")
    return array.last()


@function("TAS", writes_first=True)
def _tas(rt, value: Any, new):
    """TAS(var, new): the old value, and var set to `new` in the same step (tasks
    switch only between steps here, so it is atomic)."""
    return value, float(new)


@function("CAS", writes_first=True)
def _cas(rt, value: Any, test, new):
    """CAS(var, test, new): the old value; var becomes `new` only if it equalled `test`."""
    return value, (float(new) if value == test else value)


# ---- analog I/O: the twin's cell has no analog board
@function("AIO.INS")
def _aio_ins(rt, channel):
    to_int(channel)
    return FALSE


@function("AIO.IN")
def _aio_in(rt, channel):
    raise fail(msg.DEVICE_NOT_READY, f"no analog input {to_int(channel)} is installed")


@instruction("AIO.OUT")
def _aio_out(rt, value, channel):
    raise fail(msg.DEVICE_NOT_READY, f"no analog output {to_int(channel)} is installed")


@function("$ID")
def _id_text(rt, *args: Any):
    return SYSTEM_ID


@function("ID")
def _id(rt, *args: Any):
    return 0.0  # no hardware option boards to identify


@function("FREE")
def _free(rt, *args: Any):
    return 100.0  # percent of program memory free: memory never runs out here


@function("$DEFAULT")
def _default(rt, *args: Any):
    return "DISK>"  # the sandbox root is the default disk and path
