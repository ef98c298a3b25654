"""Data sections in program files: .LOCATIONS, .REALS, .STRINGS (and .DOUBLES).

The user's guides name the commands that write them (STOREL, STORER, STORES)
but not their layout; we accept the layout those commands write:
  .LOCATIONS   name  x y z yaw pitch roll        (a transformation)
               #name j1 j2 j3 j4 ...             (a precision point)
  .REALS       name = value        .STRINGS   $name = "text"
Array elements are written name[i].  Values may be separated by spaces or commas.
"""

from __future__ import annotations

import math
import re

from ...controller.location import Location
from ...errors import ProgramError
from . import ast
from . import messages as msg
from .parser import normalize_name, parse_number
from .values import MAX_STRING, VArray, single

_ENTRY = re.compile(r"^([$#]?[A-Za-z][A-Za-z0-9._]*)(?:\[([0-9, ]+)\])?\s*=?\s*(.*)$")


def _store(table: dict, name: str, index: str | None, value) -> None:
    if index is None:
        table[name] = value
        return
    parts = tuple(int(i) for i in index.split(","))
    array = table.setdefault(name + "[]", VArray())
    array[parts[0] if len(parts) == 1 else parts] = value


def load_data_section(section: ast.DataSection, table: dict) -> None:
    for line, text in section.lines:
        text = text.split(";", 1)[0].strip()
        if not text:
            continue
        match = _ENTRY.match(text)
        where = {"file": section.file, "line": line, "column": 1, "text": text}
        try:
            if match is None:
                raise ValueError(text)
            name, index, rest = normalize_name(match[1]), match[2], match[3].strip()
            if (name[0] == "$") != (section.kind == "STRINGS") or (name[0] == "#" and section.kind != "LOCATIONS"):
                raise ProgramError(f"{msg.message(msg.WRONG_TYPE)} {name} in .{section.kind}", msg.WRONG_TYPE,
                                   **where)
            if section.kind == "STRINGS":
                if not (rest.startswith('"') and rest.endswith('"')):
                    raise ValueError(rest)
                value = rest[1:-1]
                if len(value) > MAX_STRING:
                    raise ProgramError(msg.message(msg.STRING_TOO_LONG), msg.STRING_TOO_LONG, **where)
            else:
                numbers = [parse_number(t) for t in re.split(r"[\s,]+", rest) if t]
                if not all(math.isfinite(n) for n in numbers):
                    raise OverflowError
                if section.kind == "LOCATIONS":
                    value = tuple(numbers) if name.startswith("#") else Location(*numbers)
                else:
                    (value,) = numbers
                    if section.kind == "REALS":
                        value = single(value)  # .DOUBLES keep 64 bits
        except OverflowError:  # beyond the range of a real ([000] L3868-3895)
            raise ProgramError(f"{msg.message(msg.OVERFLOW)} in a .{section.kind} entry", msg.OVERFLOW,
                               **where) from None
        except (ValueError, TypeError):
            raise ProgramError(
                f"{msg.message(msg.SYNTAX_ERROR)} bad {section.kind.lower()} entry", msg.SYNTAX_ERROR, **where,
            ) from None
        _store(table, name, index, value)
