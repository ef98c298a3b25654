"""String functions."""

from __future__ import annotations

from ..values import to_int
from . import function


@function("VAL")
def _val(rt, text):
    from ..runtime import parse_real

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
    from ..formats import render

    return render(items)[0]
