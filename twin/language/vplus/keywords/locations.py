"""Location (transformation) functions."""

from __future__ import annotations

import math

import numpy as np

from ....controller.belt import BeltFrame, BeltLocation
from ....controller.location import NULL, Location, trans
from .. import messages as msg
from ..values import FALSE, TRUE, components, fail
from . import Any, Loc, function, instruction

DEG = math.pi / 180.0


def location_arg(value) -> Location:
    """A transformation argument; a belt location (%belt:loc) is where its belt is now."""
    if isinstance(value, BeltLocation):
        return value.instantaneous()
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
def _inverse(rt, loc: Any):
    # HERE %belt:loc is SET loc = INVERSE(%belt):HERE: the belt frame where it is now.
    if isinstance(loc, BeltFrame):
        return loc.instantaneous().inverse()
    return location_arg(loc).inverse()


@function("SHIFT")
def _shift(rt, loc: Loc, dx=0.0, dy=0.0, dz=0.0):
    return location_arg(loc).shifted(dx or 0.0, dy or 0.0, dz or 0.0)


@function("HERE")
def _here(rt):
    return rt.robot.here()


@function("DEST")
def _dest(rt):
    return rt.robot.destination()


@function("#PHERE")
def _phere(rt):
    """#PHERE: where the robot is now, as a precision point (measured joints)."""
    return rt.robot.to_user_joints(rt.robot.joints())


@function("#PDEST")
def _pdest(rt):
    """#PDEST: where the robot was last told to go, as a precision point."""
    return rt.robot.to_user_joints(rt.robot.destination_joints())


@function("DX")
def _dx(rt, loc: Loc):
    return location_arg(loc).x


@function("DY")
def _dy(rt, loc: Loc):
    return location_arg(loc).y


@function("DZ")
def _dz(rt, loc: Loc):
    return location_arg(loc).z


@function("DISTANCE")
def _distance(rt, a: Loc, b: Loc):
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


@function("FRAME")
def _frame(rt, x1: Loc, x2: Loc, y: Loc, origin: Loc):
    """FRAME(p1, p2, p3, p4): X from p1 towards p2, Y in the plane of p3 on its
    +Y side, origin at p4 (V+ guide v17, "Defining a Reference Frame")."""
    p1, p2, p3, p4 = (location_arg(p).position() for p in (x1, x2, y, origin))
    x_axis = p2 - p1
    if np.linalg.norm(x_axis) < 1e-9:
        raise fail(msg.ILLEGAL_VALUE, "FRAME: the first two points coincide")
    x_axis = x_axis / np.linalg.norm(x_axis)
    y_axis = (p3 - p1) - np.dot(p3 - p1, x_axis) * x_axis
    if np.linalg.norm(y_axis) < 1e-9:
        raise fail(msg.ILLEGAL_VALUE, "FRAME: the three points are in line")
    y_axis = y_axis / np.linalg.norm(y_axis)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x_axis, y_axis, np.cross(x_axis, y_axis), p4
    return Location.from_matrix(m)


@function("SCALE")
def _scale(rt, loc: Loc, factor):
    """SCALE(t BY k): the position multiplied by k, the orientation kept."""
    loc = location_arg(loc)
    return Location(loc.x * factor, loc.y * factor, loc.z * factor, loc.yaw, loc.pitch, loc.roll)


@function("NORMAL")
def _normal(rt, loc: Loc):
    # A Location is rebuilt from its angles every time, so its rotation is
    # always orthonormal: there is no round-off to remove.
    return location_arg(loc)


@function("IDENTICAL")
def _identical(rt, a: Loc, b: Loc):
    """True when the two transformations are the same (to 1e-6 of a mm or a degree
    in their matrices, the canonical angles being rebuilt from them)."""
    same = np.allclose(location_arg(a).matrix(), location_arg(b).matrix(), atol=1e-6)
    return TRUE if same else FALSE


@function("#PPOINT")
def _ppoint(rt, *joints):
    """#PPOINT(j1, j2, ...): a precision point (one value per joint)."""
    return tuple(0.0 if j is None else float(j) for j in joints)


@instruction("DECOMPOSE", targets=True)
def _decompose(rt, value: Any, target: Any):
    """DECOMPOSE a[i] = loc: x, y, z, yaw, pitch, roll (or a precision point's
    joints) into a[i], a[i+1], ..."""
    if isinstance(value, Location):
        parts = components(value)
    elif isinstance(value, tuple):
        parts = value
    else:
        raise fail(msg.WRONG_TYPE, "location expected")
    if not isinstance(target, tuple):
        raise fail(msg.WRONG_TYPE, "DECOMPOSE needs an array")
    array, start = target
    start = start or 0
    for i, part in enumerate(parts):
        array[start + i] = float(part)
