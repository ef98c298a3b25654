"""GPL's language built-ins: conversion and string functions (ch. 4 Table 4-3,
ch. 6 "Built-in Functions", ch. 7 Table 7-2), String members (Table 7-1), the
Math class (Table 6-2) and the Exception class (ch. 11, Table 11-1).

Math's trigonometric functions work in degrees, like every other angle in GPL
(Yaw/Pitch/Roll, joint angles); the manual does not say (docs/gpl.md).
"""

from __future__ import annotations

import decimal
import math
import struct

from .errors import INVALID_ARGUMENT, INVALID_EXCEPTION, GplError, fail, message
from .library import gpl_class, shared
from .library.members import stored
from .values import (
    GplArray, _cbool, _cbyte, _cdbl, _cint, _csng, _cshort, _cstr, _ix, _num, format_value,
)


def _hex(v) -> str:
    return format(_cint(v) & 0xFFFFFFFF, "X")


def _fix(v):
    return float(math.trunc(_num(v)))


def _int(v):
    return float(math.floor(_num(v)))


def _chr(v) -> str:
    """Chr: the low 8 bits of the truncated code (Chr(block / 256) in the TFTP example)."""
    return chr(int(_num(v)) & 0xFF)


def _asc(s) -> int:
    s = _cstr(s)
    if not s:
        raise fail(INVALID_ARGUMENT, "Asc of an empty String")
    return ord(s[0])


def _instr(start, text, sought) -> int:
    """Instr: 1-based position of `sought` in `text` from `start`, 0 if absent."""
    pos = _cstr(text).find(_cstr(sought), max(_ix(start) - 1, 0))
    return pos + 1


def _mid(s, first, length=None) -> str:
    s = _cstr(s)
    start = max(_ix(first) - 1, 0)
    return s[start:] if length is None else s[start:start + max(_ix(length), 0)]


def _rounded(number: float, decimals: int) -> str:
    """`number` with `decimals` places, a half rounded away from zero as VB's Format does
    (Format(3.125, "0.00") is "3.13"), from the shortest text that reads back as the number."""
    exact = decimal.Decimal(repr(float(number)))
    with decimal.localcontext() as ctx:
        ctx.prec = 400
        return f"{exact.quantize(decimal.Decimal(1).scaleb(-decimals), rounding=decimal.ROUND_HALF_UP):f}"


def _format(value, spec) -> str:
    """Format(expr, "0.00"): VB-style digit placeholders: 0 (always) and # (if any)."""
    spec = _cstr(spec)
    number = _num(value)
    whole, _, frac = spec.partition(".")
    decimals = len(frac.replace(",", ""))
    text = _rounded(abs(number), decimals)
    int_part, _, frac_part = text.partition(".")
    min_digits = whole.count("0")
    int_part = int_part.lstrip("0").rjust(min_digits, "0") if min_digits or int_part != "0" else ""
    if "," in whole:
        int_part = f"{int(int_part or 0):,}" if int_part else ""
    keep = len(frac.rstrip("#"))
    frac_part = frac_part[:keep] + frac_part[keep:].rstrip("0")
    out = int_part + ("." + frac_part if frac_part else "")
    return ("-" if number < 0 and out.strip("0.") else "") + (out or "0")


# Type codes of ToBitString/FromBitString (twin-defined: the manual gives no numbers).
_BIT_FORMATS = {0: "b", 1: "B", 2: "h", 3: "i", 4: "f", 5: "d", 6: "H", 7: "I"}


def _to_bits(value, kind, big_endian=False) -> str:
    fmt = _BIT_FORMATS.get(_ix(kind))
    if fmt is None:
        raise fail(INVALID_ARGUMENT, f"bit string type {kind}")
    number = _num(value)
    if fmt not in "fd":
        number = int(round(number))
    return struct.pack((">" if _cbool(big_endian) else "<") + fmt, number).decode("latin-1")


def _from_bits(text, kind, big_endian=False):
    fmt = _BIT_FORMATS.get(_ix(kind))
    if fmt is None:
        raise fail(INVALID_ARGUMENT, f"bit string type {kind}")
    raw = _cstr(text).encode("latin-1")[: struct.calcsize(fmt)]
    return struct.unpack((">" if _cbool(big_endian) else "<") + fmt, raw)[0]


def _rnd(rt, seed=1.0) -> float:
    """Rnd(seed): VB semantics: < 0 reseeds, 0 repeats the last number, > 0 the next."""
    seed = _num(seed)
    if seed < 0:
        rt.random.seed(seed)
    elif seed == 0 and rt.last_random is not None:
        return rt.last_random
    rt.last_random = rt.random.random()
    return rt.last_random


# name -> (function, takes rt)
FUNCTIONS: dict[str, tuple] = {
    "cbool": (_cbool, False), "cbyte": (_cbyte, False), "cdbl": (_cdbl, False), "cint": (_cint, False),
    "cshort": (_cshort, False), "csng": (_csng, False), "cstr": (_cstr, False), "hex": (_hex, False),
    "fix": (_fix, False), "int": (_int, False), "rnd": (_rnd, True), "asc": (_asc, False),
    "chr": (_chr, False), "format": (_format, False), "instr": (_instr, False),
    "lcase": (lambda s: _cstr(s).lower(), False), "ucase": (lambda s: _cstr(s).upper(), False),
    "len": (lambda s: len(_cstr(s)), False), "mid": (_mid, False),
    "tobitstring": (_to_bits, False), "frombitstring": (_from_bits, False),
}
# Functions whose result type the compiler knows.
FUNCTION_TYPES = {
    "cbool": "boolean", "cbyte": "byte", "cdbl": "double", "cint": "integer", "cshort": "short",
    "csng": "single", "cstr": "string", "hex": "string", "fix": "double", "int": "double",
    "rnd": "double", "asc": "integer", "chr": "string", "format": "string", "instr": "integer",
    "lcase": "string", "ucase": "string", "len": "integer", "mid": "string", "tobitstring": "string",
}


# ------------------------------------------------------------- String members
def _trim_chars(args) -> str | None:
    return "".join(_cstr(a) for a in args) if args else None


def _split(s, *separators) -> GplArray:
    text = _cstr(s)
    seps = "".join(_cstr(x) for x in separators) or " "
    parts, current = [], []
    for ch in text:
        if ch in seps:
            parts.append("".join(current))
            current = []
        else:
            current.append(ch)
    parts.append("".join(current))
    return GplArray.of(parts, "")


def _substring(s, first, length=None) -> str:
    s = _cstr(s)
    start = _ix(first)
    if start < 0 or start > len(s):
        raise fail(INVALID_ARGUMENT, f"Substring start {start} of a {len(s)}-character String")
    if length is None:
        return s[start:]
    n = _ix(length)
    if n < 0 or start + n > len(s):
        raise fail(INVALID_ARGUMENT, f"Substring({start}, {n}) of a {len(s)}-character String")
    return s[start:start + n]


def _compare(a, b, ignore_case=False) -> int:
    a, b = _cstr(a), _cstr(b)
    if _cbool(ignore_case):
        a, b = a.lower(), b.lower()
    return (a > b) - (a < b)


# member -> (function(s, *args), is a property, result type)
STRING_MEMBERS: dict[str, tuple] = {
    "length": (lambda s: len(s), True, "integer"),
    "indexof": (lambda s, sub, start=0: s.find(_cstr(sub), _ix(start)), False, "integer"),
    "split": (_split, False, None),
    "substring": (_substring, False, "string"),
    "tolower": (lambda s: s.lower(), False, "string"),
    "toupper": (lambda s: s.upper(), False, "string"),
    "trim": (lambda s, *c: s.strip(_trim_chars(c)), False, "string"),
    "trimend": (lambda s, *c: s.rstrip(_trim_chars(c)), False, "string"),
    "trimstart": (lambda s, *c: s.lstrip(_trim_chars(c)), False, "string"),
}
STRING_SHARED = {"compare": _compare}


# --------------------------------------------------------------------- Math
@gpl_class("Math")
class Math:
    """Table 6-2.  Angles in degrees."""

    Abs = shared(lambda rt, x: abs(_num(x)))
    Acos = shared(lambda rt, x: math.degrees(math.acos(_num(x))))
    Asin = shared(lambda rt, x: math.degrees(math.asin(_num(x))))
    Atan = shared(lambda rt, x: math.degrees(math.atan(_num(x))))
    Atan2 = shared(lambda rt, y, x: math.degrees(math.atan2(_num(y), _num(x))))
    Ceiling = shared(lambda rt, x: float(math.ceil(_num(x))))
    Cos = shared(lambda rt, x: math.cos(math.radians(_num(x))))
    Cosh = shared(lambda rt, x: math.cosh(_num(x)))
    E = shared(lambda rt: math.e)
    Exp = shared(lambda rt, x: math.exp(_num(x)))
    Floor = shared(lambda rt, x: float(math.floor(_num(x))))
    Log = shared(lambda rt, x: _log(math.log, x))
    Log10 = shared(lambda rt, x: _log(math.log10, x))
    Max = shared(lambda rt, a, b: max(_num(a), _num(b)))
    Min = shared(lambda rt, a, b: min(_num(a), _num(b)))
    PI = shared(lambda rt: math.pi)
    Pow = shared(lambda rt, a, b: float(_num(a)) ** _num(b))
    Sign = shared(lambda rt, x: (_num(x) > 0) - (_num(x) < 0))
    Sin = shared(lambda rt, x: math.sin(math.radians(_num(x))))
    Sinh = shared(lambda rt, x: math.sinh(_num(x)))
    Sqrt = shared(lambda rt, x: _sqrt(x))
    Tan = shared(lambda rt, x: math.tan(math.radians(_num(x))))
    Tanh = shared(lambda rt, x: math.tanh(_num(x)))


def _log(fn, x) -> float:
    x = _num(x)
    if x <= 0:
        raise fail(INVALID_ARGUMENT, f"logarithm of {format_value(x)}")
    return fn(x)


def _sqrt(x) -> float:
    x = _num(x)
    if x < 0:
        raise fail(INVALID_ARGUMENT, f"square root of {format_value(x)}")
    return math.sqrt(x)


# ---------------------------------------------------------------- Exception
def _library_messages() -> dict[int, str]:
    """The built-in classes' (code, message) pairs (library/codes.py) and the other
    controller codes programs throw, by code."""
    from .library import codes

    messages = dict(codes.CONTROLLER_MESSAGES)
    messages.update({v[0]: v[1] for v in vars(codes).values()
                     if isinstance(v, tuple) and len(v) == 2 and isinstance(v[0], int) and isinstance(v[1], str)})
    return messages



@gpl_class("Exception")
class GplException:
    """Table 11-1.  `New Exception` is empty; `New Exception(code[, qualifier])`
    (twin: the dictionary's optional arguments) sets the code for a Throw."""

    def __init__(self, rt=None, code=0, qualifier=0):
        self._code = _cint(code)
        self._qualifier = _cint(qualifier)
        self._robot_error = False
        self._robot_num = 0
        self._axis = 0
        self._text = None  # the original message of a caught error

    @staticmethod
    def from_error(err: GplError) -> "GplException":
        thrown = getattr(err, "gpl_exception", None)
        if thrown is not None:
            return thrown.Clone()
        exc = GplException()
        exc._code = err.code
        exc._text = err.message
        return exc

    def to_error(self) -> GplError:
        if self._code == 0:
            return fail(INVALID_EXCEPTION, "Throw of an Exception with ErrorCode 0")
        err = GplError(self._code, self.Message())
        err.gpl_exception = self.Clone()
        return err

    @property
    def ErrorCode(self) -> int:
        return self._code

    @ErrorCode.setter
    def ErrorCode(self, value) -> None:
        self._code = _cint(value)
        self._text = None

    Qualifier = stored("_qualifier", _cint)
    RobotError = stored("_robot_error", _cbool)
    RobotNum = stored("_robot_num", _cint)
    Axis = stored("_axis", _cint)

    def Message(self) -> str:
        """The full text: `*message*` with the robot or qualifier details (twin format)."""
        text = self._text or _library_messages().get(self._code) or message(self._code)
        if self._robot_error:
            text += f": Robot {self._robot_num}" + (f": Axis &H{self._axis:X}" if self._axis else "")
        return text

    def Clone(self) -> "GplException":
        copy = GplException()
        copy._code, copy._qualifier, copy._robot_error = self._code, self._qualifier, self._robot_error
        copy._robot_num, copy._axis, copy._text = self._robot_num, self._axis, self._text
        return copy

    def UpdateErrorCode(self, code=None) -> None:
        """With a code: the Exception's code becomes it.  Without one (GPL Dictionary), a
        general code is replaced by the controller's more specific one; the twin's errors
        are already the specific ones, so the code stays."""
        if code is not None:
            self.ErrorCode = code
