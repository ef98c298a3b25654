"""V+ values and the operations the generated code calls.

Reals are Python floats, strings are `str`, transformations are
`controller.location.Location`, arrays are `VArray` dictionaries keyed by the
(rounded) index or index tuple.  V+ truth values are -1.0 and 0.0.
"""

from __future__ import annotations

import math
import struct

from ...controller.belt import BeltFrame, BeltLocation
from ...controller.location import Location
from ...errors import ProgramError
from . import messages as msg

TRUE = -1.0
FALSE = 0.0
MAX_STRING = 128  # V+ guide v17, "String Data Type": 0..128 characters
_SINGLE = struct.Struct("<f")


class VArray(dict):
    """A V+ array: allocated on first assignment, grows as needed, indices from 0."""

    def last(self) -> float:
        """LAST(): the highest index used in the first dimension (-1 if none)."""
        if not self:
            return -1.0
        return float(max(k if isinstance(k, int) else k[0] for k in self))


def fail(code: int, detail: str = "") -> ProgramError:
    return ProgramError(msg.message(code) + (f" {detail}" if detail else ""), code)


def _ix(value) -> int:
    """An array index: reals are rounded, not truncated (V+ guide v17, "Integers")."""
    try:
        index = math.floor(value + 0.5)
    except TypeError:
        raise fail(msg.WRONG_TYPE, "array index") from None
    if index < 0:
        raise fail(msg.ILLEGAL_ARRAY_INDEX, str(index))
    return index


def _div(a, b):
    if b == 0:
        raise fail(msg.DIVIDE_BY_ZERO)
    return a / b


def _mod(a, b):
    if b == 0:
        raise fail(msg.DIVIDE_BY_ZERO)
    return math.fmod(a, b)  # the remainder takes the sign of the dividend


def to_int(value) -> int:
    if isinstance(value, str) or isinstance(value, Location):
        raise fail(msg.WRONG_TYPE)
    return math.floor(value + 0.5)


def _com(a) -> float:
    return float(~to_int(a))


def _bitwise(op: str, a, b) -> float:
    x, y = to_int(a), to_int(b)
    return float(x & y if op == "BAND" else x | y if op == "BOR" else x ^ y)


def _strcmp(rt, a, b, op: str) -> bool:
    if not isinstance(a, str) or not isinstance(b, str):
        raise fail(msg.WRONG_TYPE, "string comparison")
    if rt.switch("UPPER"):  # UPPER (default on): comparisons ignore case
        a, b = a.upper(), b.upper()
    return {"==": a == b, "<>": a != b, "<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b}[op]


def _str(value) -> str:
    if not isinstance(value, str):
        raise fail(msg.WRONG_TYPE, "string expected")
    if len(value) > MAX_STRING:
        raise fail(msg.STRING_TOO_LONG)
    return value


def _real(value) -> float:
    """A real argument or value: a string, location, precision point or array is
    *Wrong data type*."""
    if isinstance(value, float):
        if value - value == 0.0:  # finite
            return value
        # An infinity from 64-bit arithmetic inside an expression (a single store rounds
        # but does not check it, to keep stores cheap): any use of it is an overflow.
        raise fail(msg.OVERFLOW, "beyond the range of a real")
    if isinstance(value, int):
        return float(value)
    raise fail(msg.WRONG_TYPE, "real value expected")


def single(value: float) -> float:
    """A real as a (32-bit IEEE) single-precision V+ real holds it: reals are
    single precision unless declared DOUBLE (V+ guide v17 L3868-3895)."""
    return _SINGLE.unpack(_SINGLE.pack(value))[0]


def _single(value) -> float:
    """Store into a real variable: a real, rounded to single precision."""
    try:
        return _SINGLE.unpack(_SINGLE.pack(value))[0]
    except OverflowError:
        raise fail(msg.OVERFLOW, f"{value:g} is beyond single precision") from None
    except struct.error:
        raise fail(msg.WRONG_TYPE, "real value expected") from None


def _argument(value, kind: str, name: str):
    """A CALL argument for parameter `name`: a string for a $ parameter, an
    array for a[], a real or location (not a string) for the others."""
    if kind == "array":
        ok = isinstance(value, VArray)
    else:
        ok = isinstance(value, str) == (kind == "string") and not isinstance(value, VArray)
    if not ok:
        raise fail(msg.WRONG_TYPE, f"argument for {name}")
    return value


def _location(value) -> Location:
    """A transformation; a belt location (%belt:loc) is where its belt has it now."""
    if isinstance(value, BeltLocation):
        return value.instantaneous()
    if not isinstance(value, Location):
        raise fail(msg.WRONG_TYPE, "location expected")
    return value


def _point(value):
    """Where a motion may go: a transformation, a precision point or a belt location."""
    if not isinstance(value, (Location, tuple, BeltLocation)):
        raise fail(msg.WRONG_TYPE, "location expected")
    return value


def _precision_point(value) -> tuple:
    """SET #p = ...: a precision point is a tuple of joint values."""
    if not isinstance(value, tuple):
        raise fail(msg.WRONG_TYPE, "precision point expected")
    return value


def _turn(angle: float) -> float:
    """An angle in (-180, 180]."""
    angle = math.fmod(angle, 360.0)
    return angle - 360.0 if angle > 180.0 else angle + 360.0 if angle <= -180.0 else angle + 0.0


def components(loc: Location) -> tuple[float, ...]:
    """x, y, z, yaw, pitch, roll as V+ shows them: every angle within +-180 and pitch signed,
    "a positive rotation of 190 degrees is shown as -170" ([000] L6018-6019, [001] L2216).
    Of the two equal triples (y, p, r) and (y + 180, -p, r + 180) the one with yaw in
    (-90, 90] is shown; pitch 0 or 180 keeps yaw 0 (the SCARA form: the tool straight down
    has pitch 180 and its turn in roll)."""
    x, y, z, yaw, pitch, roll = loc.components()
    if pitch not in (0.0, 180.0) and not -90.0 < yaw <= 90.0:
        yaw, pitch, roll = _turn(yaw + 180.0), -pitch, _turn(roll + 180.0)
    return x, y, z, yaw, pitch, roll


def _compound(a, b) -> Location | BeltLocation:
    """a:b.  A belt variable may only be the leftmost element: %belt:loc is a location
    fixed to the belt (eV+ guide, "Belt-Relative Motion Instructions")."""
    if isinstance(b, (BeltFrame, BeltLocation)):
        raise fail(msg.ILLEGAL_OPERATION, "a belt variable must be the leftmost element of a compound location")
    if isinstance(a, BeltFrame):
        return BeltLocation(a, _location(b))
    if isinstance(a, BeltLocation):
        return a * _location(b)
    return _location(a) * _location(b)


def _array(table: dict, key: str) -> VArray:
    array = table.get(key)
    if array is None:
        array = table[key] = VArray()
    return array


class AutoArray(VArray):
    """An AUTO array: it has the size its declaration gives (the highest index
    of each dimension) and, unlike GLOBAL and LOCAL arrays, does not grow
    ([000] L3995-3997, L4028-4030)."""

    def __init__(self, limits: tuple[int, ...]):
        super().__init__()
        self.limits = limits

    def __setitem__(self, index, value) -> None:
        indices = index if isinstance(index, tuple) else (index,)
        if len(indices) != len(self.limits) or any(i > limit for i, limit in zip(indices, self.limits)):
            raise fail(msg.ILLEGAL_ARRAY_INDEX, f"{list(indices)} beyond AUTO array size {list(self.limits)}")
        super().__setitem__(index, value)


def _auto_array(limits: tuple[int, ...]) -> AutoArray:
    return AutoArray(limits)


def _defined_element(table: dict, key: str, index) -> float:
    array = table.get(key)
    return TRUE if array is not None and index in array else FALSE


def _no_wait(mode) -> bool:
    """GETC's and READ's mode: bit 1 (value 1) is no-wait."""
    return bool(to_int(mode) & 1)


def _element_or_none(table: dict, key: str, index):
    """An array element passed to CALL by reference: its value, or None while
    it (or its array) is undefined, which the callee sees as undefined."""
    array = table.get(key)
    return None if array is None else array.get(index)


def _program_name(value) -> str:
    """CALLS: the program named by a string."""
    from .parser import normalize_name

    name = _str(value).strip()
    if not name:
        raise fail(msg.UNDEFINED_PROGRAM, "empty program name")
    return normalize_name(name)


def truth(value) -> float:
    return TRUE if value else FALSE
