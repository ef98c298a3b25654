"""Location (transformation) functions."""

from __future__ import annotations

import math

import numpy as np

from ....controller.location import NULL, Location, trans
from .. import messages as msg
from ..values import fail
from . import function

DEG = math.pi / 180.0


def location_arg(value) -> Location:
    if not isinstance(value, Location):
        raise fail(msg.WRONG_TYPE, "location expected")
    return value


@function("TRANS")
def _trans(rt, x=0.0, y=0.0, z=0.0, yaw=0.0, pitch=0.0, roll=0.0):
    return trans(*(0.0 if v is None else v for v in (x, y, z, yaw, pitch, roll)))


@function("NULL")
def _null(rt):
    return NULL


@function("INVERSE")
def _inverse(rt, loc):
    return location_arg(loc).inverse()


@function("SHIFT")
def _shift(rt, loc, dx=0.0, dy=0.0, dz=0.0):
    return location_arg(loc).shifted(dx or 0.0, dy or 0.0, dz or 0.0)


@function("HERE")
def _here(rt):
    return rt.robot.here()


@function("DEST")
def _dest(rt):
    return rt.robot.destination()


@function("DX")
def _dx(rt, loc):
    return location_arg(loc).x


@function("DY")
def _dy(rt, loc):
    return location_arg(loc).y


@function("DZ")
def _dz(rt, loc):
    return location_arg(loc).z


@function("DISTANCE")
def _distance(rt, a, b):
    a, b = location_arg(a), location_arg(b)
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
    c, s = math.cos(angle * DEG), math.sin(angle * DEG)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(4)
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = -s, s
    return m
