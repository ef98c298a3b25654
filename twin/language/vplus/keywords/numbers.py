"""Numeric and logical functions (V+ trigonometry works in degrees)."""

from __future__ import annotations

import math

from .. import messages as msg
from ..values import FALSE, TRUE, fail
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
