"""GPL values and the operations generated code calls.

Representation (User Manual ch. 4): Integer, Short and Byte are Python ints
kept in range on assignment; Double and Single are floats (a Single is
rounded to 32 bits); Boolean is bool, but counts as -1 in arithmetic (`Not
False` is -1, Table 6-1); String is str; Nothing is None; arrays are
GplArray; objects are Python objects.  Most arithmetic is done in Double
(ch. 6, 5.1.1) and converted to the target's type when stored, integers by
rounding (ch. 8: 7.875 stored in an Integer is 8).
"""

from __future__ import annotations

import itertools
import math
import struct

from .errors import ARITHMETIC_OVERFLOW, DIVIDE_BY_ZERO, INVALID_NUMBER, OUT_OF_MEMORY, OVERFLOW, SUBSCRIPT_RANGE, TYPE_MISMATCH, fail

# The controller's memory, as limits (docs/gpl.md): an array has at most this many
# elements, a String at most this many characters; beyond, -711 *Out of memory*.
MAX_ARRAY_ELEMENTS = 1 << 22
MAX_STRING_LENGTH = 1 << 24
DOUBLE_MAX = 1.7976931348623157e308
SINGLE_MAX = 3.4028234663852886e38
INTEGER_RANGES = {"integer": (-(2**31), 2**31 - 1), "short": (-32768, 32767), "byte": (0, 255)}


class GplArray:
    """A GPL array: rank 1-4, every lower bound 0, `dims` the upper bounds."""

    __slots__ = ("dims", "data", "element")

    def __init__(self, dims: tuple[int, ...], default):
        self.dims = dims
        size = 1
        for d in dims:
            if d < -1:
                raise fail(SUBSCRIPT_RANGE, f"upper bound {d}")
            size *= d + 1
        if size > MAX_ARRAY_ELEMENTS:
            raise fail(OUT_OF_MEMORY, f"an array of {size:,} elements (at most {MAX_ARRAY_ELEMENTS:,})")
        self.data = [default] * size
        self.element = default

    def _offset(self, index) -> int:
        if type(index) is tuple:
            if len(index) != len(self.dims):
                raise fail(SUBSCRIPT_RANGE, f"{len(index)} indices for a rank {len(self.dims)} array")
            offset = 0
            for i, d in zip(index, self.dims):
                if not 0 <= i <= d:
                    raise fail(SUBSCRIPT_RANGE, str(i))
                offset = offset * (d + 1) + i
            return offset
        if len(self.dims) != 1 or not 0 <= index <= self.dims[0]:
            raise fail(SUBSCRIPT_RANGE, str(index))
        return index

    def __getitem__(self, index):
        return self.data[self._offset(index)]

    def __setitem__(self, index, value) -> None:
        self.data[self._offset(index)] = value

    def __len__(self) -> int:
        return len(self.data)

    def __iter__(self):
        return iter(self.data)

    # Array class members (Table 4-5)
    @property
    def Length(self) -> int:
        return len(self.data)

    @property
    def Rank(self) -> int:
        return len(self.dims)

    def GetUpperBound(self, dimension) -> int:
        d = _ix(dimension)
        if not 0 <= d < len(self.dims):
            raise fail(SUBSCRIPT_RANGE, f"dimension {d}")
        return self.dims[d]

    def redim(self, dims: tuple[int, ...], preserve: bool = False) -> None:
        """ReDim: new sizes, same rank; the elements are reset, or with Preserve the ones
        whose indices are inside both the old and the new bounds are kept."""
        if len(dims) != len(self.dims):
            raise fail(SUBSCRIPT_RANGE, "ReDim cannot change the rank of an array")
        fresh = GplArray(dims, self.element)
        if preserve:
            for index in itertools.product(*(range(min(a, b) + 1) for a, b in zip(self.dims, dims))):
                fresh[index if len(index) > 1 else index[0]] = self[index if len(index) > 1 else index[0]]
        self.dims, self.data = fresh.dims, fresh.data

    @staticmethod
    def of(values: list, default) -> "GplArray":
        array = GplArray((len(values) - 1,), default)
        array.data = list(values)
        return array


# ---------------------------------------------------------------- conversions
class Single(float):
    """A Single's value: a float rounded to 32 bits, marked so that CStr, & and Console
    show it as a Single (7 significant digits).  Arithmetic on it gives a plain float
    (a Double, ch. 6: most arithmetic is done in Double)."""

    __slots__ = ()


def _num(v):
    """A value as a number for arithmetic: Booleans are -1/0, Strings are parsed."""
    t = v.__class__
    if t is int or t is float:
        return v
    if t is Single:
        return float(v)
    if t is bool:
        return -1 if v else 0
    if t is str:
        return parse_number(v)
    if v is None:
        raise fail(TYPE_MISMATCH, "Nothing used as a number")
    raise fail(TYPE_MISMATCH, f"{type(v).__name__} used as a number")


def parse_number(text: str) -> float:
    s = text.strip()
    try:
        if s[:2].lower() == "&h":
            return float(int(s[2:], 16))
        if s[:2].lower() == "&o":
            return float(int(s[2:], 8))
        return float(s)
    except ValueError:
        raise fail(INVALID_NUMBER, repr(text)) from None


def _round_int(v, kind: str) -> int:
    """Round half to even, as VB.NET's CInt does, then check the type's range."""
    if v.__class__ is not int:
        v = _num(v)
        if v.__class__ is float:
            if v != v or v in (math.inf, -math.inf):
                raise fail(OVERFLOW, f"{v} as {kind.capitalize()}")
            v = round(v)
    low, high = INTEGER_RANGES[kind]
    if not low <= v <= high:
        raise fail(OVERFLOW, f"{v} as {kind.capitalize()}")
    return v


def _cint(v) -> int:
    if v.__class__ is int and -2147483648 <= v <= 2147483647:
        return v
    return _round_int(v, "integer")


def _cshort(v) -> int:
    return _round_int(v, "short")


def _cbyte(v) -> int:
    return _round_int(v, "byte")


def _cdbl(v) -> float:
    if v.__class__ is float and -DOUBLE_MAX <= v <= DOUBLE_MAX:
        return v
    v = float(_num(v))
    if not -DOUBLE_MAX <= v <= DOUBLE_MAX:
        raise fail(OVERFLOW, f"{v} as Double")
    return v


def _overflow(v, kind: str):
    """A stored operator result out of its type's range (expressions.py _RANGE_CHECKS): beyond
    the Double range it is -710 *Arithmetic overflow*, else (an Integer too large, a NaN)
    -708 *Value infinite or NAN*."""
    code = ARITHMETIC_OVERFLOW if kind == "Double" and v == v else OVERFLOW
    raise fail(code, f"{format_number(v)} as {kind}")


def format_number(v) -> str:
    return str(v) if v.__class__ is int else {math.inf: "+infinity", -math.inf: "-infinity"}.get(v, repr(v))


def _csng(v) -> Single:
    if v.__class__ is Single:
        return v
    v = _cdbl(v)
    if abs(v) > SINGLE_MAX:
        raise fail(OVERFLOW, f"{v} as Single")
    try:
        return Single(struct.unpack("f", struct.pack("f", v))[0])
    except OverflowError:
        raise fail(OVERFLOW, f"{v} as Single") from None


def _cbool(v) -> bool:
    if v.__class__ is bool:
        return v
    if v.__class__ is str:
        low = v.strip().lower()
        if low in ("true", "false"):
            return low == "true"
    return _num(v) != 0


def _cstr(v) -> str:
    if v.__class__ is str:
        return v
    return format_value(v)


def format_value(v) -> str:
    """How CStr, & and Console show a value: integers plainly, Doubles with up to 15
    significant digits, Singles with up to 7 (1E+32 style exponents), Booleans as True / False."""
    t = v.__class__
    if t is str:
        return v
    if t is bool:
        return "True" if v else "False"
    if t is int:
        return str(v)
    if t is float or t is Single:
        if not -DOUBLE_MAX <= v <= DOUBLE_MAX:  # an operation's infinity (-710) or a NaN (-708)
            raise fail(ARITHMETIC_OVERFLOW if v == v else OVERFLOW, f"{format_number(v)} as a Double")
        digits = 7 if t is Single else 15  # a Single shows 0.1, not 0.100000001490116
        if v.is_integer() and abs(v) < 10 ** digits:
            return str(int(v))
        text = f"{v:.{digits}G}"
        if "E" in text:
            mantissa, exponent = text.split("E")
            sign = exponent[0]
            digits = exponent[1:].lstrip("0") or "0"
            text = f"{mantissa}E{sign}{digits.rjust(2, '0')}"
        return text
    if v is None:
        return ""
    raise fail(TYPE_MISMATCH, f"{getattr(type(v), 'gpl_name', type(v).__name__)} used as a String")


CONVERT = {
    "integer": "_cint", "short": "_cshort", "byte": "_cbyte", "double": "_cdbl", "single": "_csng",
    "boolean": "_cbool", "string": "_cstr",
}
DEFAULTS = {"integer": 0, "short": 0, "byte": 0, "double": 0.0, "single": 0.0, "boolean": False, "string": ""}


def _ix(v) -> int:
    """An array index (reals are rounded)."""
    if v.__class__ is int:
        return v
    return _round_int(v, "integer")


# ---------------------------------------------------------------- operators
def _add(a, b):
    """`+`: concatenation when both are Strings, else numeric (ch. 7: 2.34 + "1.01" = 3.35)."""
    if a.__class__ is str and b.__class__ is str:
        return _cat(a, b)
    return _num(a) + _num(b)


def _concat(a, b) -> str:
    return _cat(_cstr(a), _cstr(b))


def _cat(a: str, b: str) -> str:
    """Two Strings joined, within the controller's memory (-711 beyond MAX_STRING_LENGTH)."""
    if len(a) + len(b) > MAX_STRING_LENGTH:
        raise fail(OUT_OF_MEMORY, f"a String of {len(a) + len(b):,} characters (at most {MAX_STRING_LENGTH:,})")
    return a + b


def _div(a, b) -> float:
    b = _num(b)
    if b == 0:
        raise fail(DIVIDE_BY_ZERO)
    quotient = _num(a) / b
    if -DOUBLE_MAX <= quotient <= DOUBLE_MAX:
        return quotient
    raise fail(ARITHMETIC_OVERFLOW, f"{_num(a)} / {b}")


def _idiv(a, b) -> int:
    """`\\`: the quotient truncated to an integer (2.3 \\ 2 = 1)."""
    b = _num(b)
    if b == 0:
        raise fail(DIVIDE_BY_ZERO)
    return int(_num(a) / b)


def _mod(a, b):
    """Mod: the real remainder, with the sign of the dividend (13.3 Mod 2 = 1.3)."""
    b = _num(b)
    if b == 0:
        raise fail(DIVIDE_BY_ZERO)
    a = _num(a)
    if a.__class__ is int and b.__class__ is int:
        return int(math.fmod(a, b))
    return math.fmod(a, b)


def _pow(a, b) -> float:
    a, b = _num(a), _num(b)
    if a < 0 and not float(b).is_integer():
        raise fail(OVERFLOW, f"{a} ^ {b}: a negative base needs an integer power")
    try:
        return float(a) ** b
    except ZeroDivisionError:
        raise fail(DIVIDE_BY_ZERO) from None
    except OverflowError:
        raise fail(ARITHMETIC_OVERFLOW) from None


def _bits(v) -> int:
    return _round_int(v, "integer") if v.__class__ is not int else v


def _shl(a, b) -> int:
    return _to32(_bits(a) << _bits(b))


def _shr(a, b) -> int:
    return _bits(a) >> _bits(b)  # Python's >> replicates the sign bit, as GPL's does


def _to32(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v >= 1 << 31 else v


def _and(a, b):
    """And: logical for two Booleans, bitwise otherwise (Table 6-1)."""
    if a.__class__ is bool and b.__class__ is bool:
        return a and b
    return _bits(_num(a)) & _bits(_num(b))


def _or(a, b):
    if a.__class__ is bool and b.__class__ is bool:
        return a or b
    return _bits(_num(a)) | _bits(_num(b))


def _xor(a, b):
    if a.__class__ is bool and b.__class__ is bool:
        return a != b
    return _bits(_num(a)) ^ _bits(_num(b))


def _not(a):
    """Not: False (0) -> True (-1), any True (<> 0) -> False (0), Table 6-1 (a Boolean
    gives a Boolean, a number the Integer -1 or 0)."""
    if a.__class__ is bool:
        return not a
    return -1 if _num(a) == 0 else 0


def _truth(v) -> bool:
    """A condition: True when <> 0 (ch. 9)."""
    if v.__class__ is bool:
        return v
    return _num(v) != 0


def _cmp(a, b, op: str) -> bool:
    """Relational operators: Strings compare binary (case-sensitive); a String
    against a number is converted to a number."""
    if a.__class__ is str and b.__class__ is str:
        pass
    elif a.__class__ is str or b.__class__ is str or a.__class__ is bool or b.__class__ is bool:
        a, b = _num(a), _num(b)
    elif a is None or b is None:
        raise fail(TYPE_MISMATCH, "Nothing compared with a relational operator (use Is)")
    if op == "=":
        return a == b
    if op == "<>":
        return a != b
    if op == "<":
        return a < b
    if op == ">":
        return a > b
    if op == "<=":
        return a <= b
    return a >= b


def _neg(a):
    return -_num(a)
