"""Numeric and logical functions (V+ guide v17, "Numeric Functions" and
"Logical Functions"; eV+ guide, same tables).  Trigonometry works in degrees.
Functions that need an integer round their argument (V+ guide v17, "Integers").
"""

from __future__ import annotations

import math

from .. import messages as msg
from ..values import FALSE, TRUE, fail, to_int
from . import function

DEG = math.pi / 180.0


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


@function("CUBRT")
def _cubrt(rt, x):
    return math.copysign(abs(x) ** (1.0 / 3.0), x)


@function("SIN")
def _sin(rt, x):
    return math.sin(x * DEG)  # V+ trigonometry is in degrees


@function("COS")
def _cos(rt, x):
    return math.cos(x * DEG)


@function("TAN")
def _tan(rt, x):
    return math.tan(x * DEG)


@function("ATAN2")
def _atan2(rt, y, x):
    return math.degrees(math.atan2(y, x))


@function("BCD")
def _bcd(rt, x):
    """BCD(x): the decimal digits of x as 4-bit groups (BCD(1234) = ^H1234)."""
    value = to_int(x)
    if not 0 <= value <= 9999_9999:
        raise fail(msg.ILLEGAL_VALUE, f"BCD({value})")
    return float(int(str(value), 16))


@function("DCB")
def _dcb(rt, x):
    """DCB(x): the number whose BCD digits x holds (DCB(^H1234) = 1234)."""
    digits = f"{to_int(x) & 0xFFFFFFFF:X}"
    if not digits.isdigit():
        raise fail(msg.ILLEGAL_VALUE, f"DCB(^H{digits}) is not BCD")
    return float(int(digits))


@function("OUTSIDE")
def _outside(rt, low, x, high):
    """OUTSIDE(low, x, high): true when x lies outside low..high."""
    return FALSE if low <= x <= high else TRUE


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
