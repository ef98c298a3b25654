"""String functions and PACK (V+ guide v17 "String-Related Functions";
eV+ guide, same table).

Strings hold bytes 0-255 (Python str with code points 0-255).  Positions are
1-based, as in $MID and POS.  Binary conversions ($INTB, LNGB, $FLTB, ...) use
big-endian byte order, the order of the controller's CPUs (68k and PowerPC).
"""

from __future__ import annotations

import re
import struct

from ....controller.location import Location
from .. import messages as msg
from ..formats import render
from ..values import MAX_STRING, _str, fail, to_int
from . import Any, Loc, Str, function, instruction

_NUMBER = re.compile(r"[ \t]*[+-]?(\d+\.?\d*|\.\d+)([Ee][+-]?\d+)?")


def leading_number(text: str) -> float:
    """VAL(): the number at the start of a string (after blanks), 0 if none."""
    match = _NUMBER.match(text)
    return float(match.group(0)) if match else 0.0


def typed_number(text: str) -> float:
    """A number typed for PROMPT into a real: the whole entry must be one
    number ([000] L10362-10368: "11+1" is *Unexpected text at end of line*,
    "++97" *Invalid number format*)."""
    match = _NUMBER.match(text)
    if match is None:
        raise fail(msg.INVALID_NUMBER, repr(text))
    if text[match.end():].strip():
        raise fail(msg.UNEXPECTED_TEXT, repr(text))
    return float(match.group(0))


def _position(start) -> int:
    """A 1-based character position as a 0-based index (0 means 1)."""
    return max(to_int(start) - 1, 0) if start is not None else 0


@function("VAL")
def _val(rt, text: Str):
    return leading_number(_str(text))


@function("LEN")
def _len(rt, text: Str):
    return float(len(_str(text)))


@function("ASC")
def _asc(rt, text: Str, index=None):
    i = _position(index)
    return float(ord(text[i])) if i < len(text) else -1.0


@function("$CHR")
def _chr(rt, code):
    value = to_int(code)
    if not 0 <= value <= 255:
        raise fail(msg.ILLEGAL_VALUE, f"$CHR({value})")
    return chr(value)


@function("$MID")
def _mid(rt, text: Str, start, count=None):
    begin = _position(start)
    return text[begin:] if count is None else text[begin : begin + max(to_int(count), 0)]


@function("POS")
def _pos(rt, text: Str, sub: Str, start=None):
    """Position of `sub` in `text` from `start` (1-based), 0 if absent."""
    found = _str(text).find(_str(sub), _position(start))
    return float(found + 1)


@function("$ENCODE")
def _encode(rt, *items: Any):
    text = render(items)[0]
    if len(text) > MAX_STRING:
        raise fail(msg.STRING_TOO_LONG)
    return text


@function("$DECODE", writes_first=True)
def _decode(rt, text: Any, breaks: Str, mode=0):
    """$DECODE($var, $breaks, mode): mode 0 returns the characters of $var up to
    the first break character, mode 1 the break characters that lead it; the
    returned characters are removed from $var."""
    text, breaks = _str(text), _str(breaks)
    take_breaks = bool(to_int(mode))
    end = 0
    while end < len(text) and (text[end] in breaks) == take_breaks:
        end += 1
    return text[:end], text[end:]


@function("$TRUNCATE")
def _truncate(rt, text: Str):
    return _str(text).split("\0", 1)[0]


# PACK and $UNPACK see a string array as one long string made of 128-character
# elements: $a[i] holds characters 1-128 counted from element i, $a[i+1] the
# next 128, and so on (V+ guide v17 "String-Related Functions": "an array of
# 128-character string variables").  Short or missing elements read as blanks.
def _span(first, count) -> tuple[int, int]:
    begin, size = _position(first), to_int(count)
    if size < 0 or size > MAX_STRING:
        raise fail(msg.ILLEGAL_VALUE, f"{size} characters")
    return begin, size


@function("$UNPACK")
def _unpack(rt, target: Any, first, count):
    """$UNPACK($a[i], first, count): `count` characters from position `first`."""
    array, index = target
    begin, size = _span(first, count)
    out = []
    for offset in range(begin, begin + size):
        element = array.get(index + offset // MAX_STRING, "")
        position = offset % MAX_STRING
        out.append(element[position] if position < len(element) else " ")
    return "".join(out)


@instruction("PACK", targets=True)
def _pack(rt, value: Str, target: Any, first, count):
    """PACK $a[i], first, count = $s: write `count` characters of $s (blank-
    padded) at position `first`, into the following elements if need be."""
    array, index = target
    begin, size = _span(first, count)
    piece = _str(value)[:size].ljust(size)
    for k, char in enumerate(piece):
        slot, position = index + (begin + k) // MAX_STRING, (begin + k) % MAX_STRING
        element = array.get(slot, "").ljust(position)
        array[slot] = element[:position] + char + element[position + 1 :]


# ---- binary conversions: bytes of a string <-> numbers
def _bytes(text: str, start, size: int) -> bytes:
    begin = _position(start)
    chunk = text[begin : begin + size]
    if len(chunk) < size:
        raise fail(msg.ILLEGAL_VALUE, f"{size} bytes needed")
    return chunk.encode("latin-1")


def _string(data: bytes) -> str:
    return data.decode("latin-1")


@function("$INTB")
def _intb_s(rt, value):
    return _string(struct.pack(">h", ((to_int(value) + 0x8000) & 0xFFFF) - 0x8000))


@function("INTB")
def _intb(rt, text: Str, start=None):
    return float(struct.unpack(">h", _bytes(text, start, 2))[0])


@function("$LNGB")
def _lngb_s(rt, value):
    return _string(struct.pack(">i", ((to_int(value) + 0x80000000) & 0xFFFFFFFF) - 0x80000000))


@function("LNGB")
def _lngb(rt, text: Str, start=None):
    return float(struct.unpack(">i", _bytes(text, start, 4))[0])


@function("$FLTB")
def _fltb_s(rt, value):
    return _string(struct.pack(">f", float(value)))


@function("FLTB")
def _fltb(rt, text: Str, start=None):
    return float(struct.unpack(">f", _bytes(text, start, 4))[0])


@function("$DBLB")
def _dblb_s(rt, value):
    return _string(struct.pack(">d", float(value)))


@function("DBLB")
def _dblb(rt, text: Str, start=None):
    return struct.unpack(">d", _bytes(text, start, 8))[0]


@function("$TRANSB")
def _transb_s(rt, loc: Loc):
    """48 bytes: the transformation's 12 matrix entries (3x3 rotation by
    columns, then the position) as singles, the layout the LRG gives."""
    if not isinstance(loc, Location):
        raise fail(msg.WRONG_TYPE, "location expected")
    m = loc.matrix()
    values = [m[r][c] for c in range(3) for r in range(3)] + [m[r][3] for r in range(3)]
    return _string(struct.pack(">12f", *values))


@function("TRANSB")
def _transb(rt, text: Str, start=None):
    values = struct.unpack(">12f", _bytes(text, start, 48))
    matrix = [[values[c * 3 + r] for c in range(3)] + [values[9 + r]] for r in range(3)] + [[0, 0, 0, 1]]
    return Location.from_matrix(matrix)
