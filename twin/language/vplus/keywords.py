"""The V+ keyword tables: instructions and functions, name -> implementation.

Like the controller's own keyword tables, a name is looked up here when the
program is compiled; an unknown instruction is a load-time error.  An
instruction that may have to wait (a motion, CLOSEI, DELAY...) is a generator
and the compiled program calls it with `yield from`.

Functions take the task (`rt`) first; motion and I/O go through the task's
robot and signal interfaces, which both languages share.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from ...controller.location import NULL, Location, approach, trans
from . import messages as msg
from .values import FALSE, TRUE, fail, to_int, truth

_DEG = math.pi / 180.0


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


# ------------------------------------------------------------------- motion
def _location_arg(value) -> Location:
    if not isinstance(value, Location):
        raise fail(msg.WRONG_TYPE, "location expected")
    return value


@instruction("MOVE", waits=True)
def _move(rt, loc):
    yield from rt.robot.move(_location_arg(loc), straight=False)


@instruction("MOVES", waits=True)
def _moves(rt, loc):
    yield from rt.robot.move(_location_arg(loc), straight=True)


@instruction("APPRO", waits=True)
def _appro(rt, loc, distance=None):
    yield from rt.robot.move(approach(_location_arg(loc), distance or 0.0), straight=False)


@instruction("APPROS", waits=True)
def _appros(rt, loc, distance=None):
    yield from rt.robot.move(approach(_location_arg(loc), distance or 0.0), straight=True)


@instruction("DEPART", waits=True)
def _depart(rt, distance):
    yield from rt.robot.move(approach(rt.robot.destination(), distance), straight=False)


@instruction("DEPARTS", waits=True)
def _departs(rt, distance):
    yield from rt.robot.move(approach(rt.robot.destination(), distance), straight=True)


@instruction("BREAK", waits=True)
def _break(rt):
    yield from rt.robot.wait_stopped()


@instruction("DELAY", waits=True)
def _delay(rt, seconds):
    yield from rt.robot.dwell(float(seconds))


@instruction("RIGHTY")
def _righty(rt):
    rt.robot.request_configuration(righty=True)


@instruction("LEFTY")
def _lefty(rt):
    rt.robot.request_configuration(righty=False)


# Hand: OPEN/CLOSE/RELAX act at the start of the next motion; the I forms wait
# for the robot to stop, act at once and then wait HAND.TIME (V+ guide v17,
# "Hand Control").
@instruction("OPEN")
def _open(rt):
    rt.robot.hand_at_next_motion("open")


@instruction("CLOSE")
def _close(rt):
    rt.robot.hand_at_next_motion("close")


@instruction("RELAX")
def _relax(rt):
    rt.robot.hand_at_next_motion("relax")


def _hand_now(rt, state: str):
    yield from rt.robot.wait_stopped()
    rt.robot.hand(state)
    yield from rt.sleep(rt.hand_time())


@instruction("OPENI", waits=True)
def _openi(rt):
    yield from _hand_now(rt, "open")


@instruction("CLOSEI", waits=True)
def _closei(rt):
    yield from _hand_now(rt, "close")


@instruction("RELAXI", waits=True)
def _relaxi(rt):
    yield from _hand_now(rt, "relax")


# ------------------------------------------------------- program control, I/O
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


# ---------------------------------------------------------------- functions
@function("TRUE")
def _true(rt):
    return TRUE


@function("ON")
def _on(rt):
    return TRUE


@function("FALSE")
def _false(rt):
    return FALSE


@function("OFF")
def _off(rt):
    return FALSE


@function("PI")
def _pi(rt):
    return math.pi


@function("ABS")
def _abs(rt, x):
    return abs(x)


@function("SQRT")
def _sqrt(rt, x):
    if x < 0:
        raise fail(msg.ILLEGAL_VALUE, "SQRT of a negative number")
    return math.sqrt(x)


@function("SQR")
def _sqr(rt, x):
    return x * x


@function("SIN")
def _sin(rt, x):
    return math.sin(x * _DEG)  # V+ trigonometry is in degrees


@function("COS")
def _cos(rt, x):
    return math.cos(x * _DEG)


@function("TAN")
def _tan(rt, x):
    return math.tan(x * _DEG)


@function("ATAN2")
def _atan2(rt, y, x):
    return math.degrees(math.atan2(y, x))


@function("INT")
def _int(rt, x):
    return float(math.trunc(x))


@function("FRACT")
def _fract(rt, x):
    return x - math.trunc(x)


@function("SIGN")
def _sign(rt, x):
    return math.copysign(1.0, x) if x else 0.0


@function("MAX")
def _max(rt, *xs):
    return max(xs)


@function("MIN")
def _min(rt, *xs):
    return min(xs)


@function("RANDOM")
def _rand(rt):
    return rt.random.random()


@function("VAL")
def _val(rt, text):
    from .runtime import parse_real

    return parse_real(text)


@function("LEN")
def _len(rt, text):
    return float(len(text))


@function("ASC")
def _asc(rt, text, index=None):
    i = to_int(index) - 1 if index is not None else 0
    return float(ord(text[i])) if 0 <= i < len(text) else -1.0


@function("$CHR")
def _chr(rt, code):
    return chr(to_int(code) & 0xFF)


@function("$MID")
def _mid(rt, text, start, count=None):
    begin = max(to_int(start) - 1, 0)
    return text[begin:] if count is None else text[begin : begin + to_int(count)]


@function("$ENCODE")
def _encode(rt, *items):
    from .formats import render

    return render(items)[0]


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


# ---------------------------------------------------------------- locations
@function("TRANS")
def _trans(rt, x=0.0, y=0.0, z=0.0, yaw=0.0, pitch=0.0, roll=0.0):
    return trans(*(0.0 if v is None else v for v in (x, y, z, yaw, pitch, roll)))


@function("NULL")
def _null(rt):
    return NULL


@function("INVERSE")
def _inverse(rt, loc):
    return _location_arg(loc).inverse()


@function("SHIFT")
def _shift(rt, loc, dx=0.0, dy=0.0, dz=0.0):
    return _location_arg(loc).shifted(dx or 0.0, dy or 0.0, dz or 0.0)


@function("HERE")
def _here(rt):
    return rt.robot.here()


@function("DEST")
def _dest(rt):
    return rt.robot.destination()


@function("DX")
def _dx(rt, loc):
    return _location_arg(loc).x


@function("DY")
def _dy(rt, loc):
    return _location_arg(loc).y


@function("DZ")
def _dz(rt, loc):
    return _location_arg(loc).z


@function("DISTANCE")
def _distance(rt, a, b):
    a, b = _location_arg(a), _location_arg(b)
    return math.dist((a.x, a.y, a.z), (b.x, b.y, b.z))


@function("RX")
def _rx(rt, angle):
    return Location.from_matrix(_rotation(0, angle))


@function("RY")
def _ry(rt, angle):
    return Location.from_matrix(_rotation(1, angle))


@function("RZ")
def _rz(rt, angle):
    return Location.from_matrix(_rotation(2, angle))


def _rotation(axis: int, angle: float):
    import numpy as np

    c, s = math.cos(angle * _DEG), math.sin(angle * _DEG)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(4)
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = -s, s
    return m
