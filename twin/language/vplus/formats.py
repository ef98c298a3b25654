"""TYPE / WRITE / $ENCODE output formatting.

The user's guides show /S, /Cn, /Un, /Xn, /B, /N and /In (V+ guide v17,
"Output Format Specifiers" in the TYPE examples; digest section 8.4).  The
numeric formats /D, /Fn.m, /En.m, /Gn.m, /Hn and /On follow the Language
Reference Guide's $ENCODE: right-justified in a field of n characters (0:
as narrow as the value allows), asterisks when the value does not fit, and a
format stays in force for the following numbers of the same statement.

The default format prints an integer-valued real without a decimal point
("The value of x is 27.") and other reals with up to 7 significant digits,
the precision of a V+ single-precision real.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...controller.location import Location
from .values import components


@dataclass(frozen=True)
class Fmt:
    code: str
    width: int | None
    decimals: int | None


def _fmt(code: str, width: int | None, decimals: int | None) -> Fmt:
    return Fmt(code, width, decimals)


def default_number(value: float) -> str:
    if value == int(value) and abs(value) < 1e15:
        return str(int(value))
    text = f"{value:.7G}"
    if "E" in text:
        mantissa, exponent = text.split("E")
        if "." in mantissa:
            mantissa = mantissa.rstrip("0").rstrip(".")
        return f"{mantissa}E{exponent}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return text


def _fit(text: str, width: int | None) -> str:
    if not width:
        return text
    if len(text) > width:
        return "*" * width
    return text.rjust(width)


def _integer(value: float) -> int:
    """Reals become integers by rounding half up, as wherever V+ needs one."""
    return math.floor(value + 0.5)


def format_number(value: float, fmt: Fmt | None) -> str:
    if fmt is None or fmt.code == "D":
        return default_number(value)
    code, width = fmt.code, fmt.width
    if code == "I":
        return _fit(str(_integer(value)), width)
    if code == "F":
        return _fit(f"{value:.{fmt.decimals or 0}f}", width)
    if code == "E":
        return _fit(f"{value:.{fmt.decimals if fmt.decimals is not None else 6}E}", width)
    if code == "G":
        return _fit(f"{value:.{fmt.decimals or 7}G}", width)
    if code == "H":
        return _fit(f"{_integer(value) & 0xFFFFFFFF:X}", width)
    if code == "O":
        return _fit(f"{_integer(value) & 0xFFFFFFFF:o}", width)
    return default_number(value)


def format_location(loc: Location) -> str:
    """A transformation as LISTL shows it: 2 decimals for X Y Z, 3 for angles."""
    x, y, z, yaw, pitch, roll = components(loc)
    return f"{x:.2f} {y:.2f} {z:.2f} {yaw:.3f} {pitch:.3f} {roll:.3f}"


def render(items: tuple) -> tuple[str, bool]:
    """The text of a TYPE item list and whether the trailing newline is wanted."""
    out: list[str] = []
    newline = True
    number_format: Fmt | None = None
    for item in items:
        if isinstance(item, Fmt):
            count = item.width if item.width is not None else 1
            if item.code == "S":
                newline = False
            elif item.code == "C":
                out.append("\n" * count)
            elif item.code == "X":
                out.append(" " * count)
            elif item.code == "B":
                out.append("\a" * count)
            elif item.code == "U":
                out.append("\x1bM" * count)  # TERMINAL type 4: cursor up with ESC M
            elif item.code == "N":
                pass  # no-wait output: the simulated terminal never blocks
            else:
                number_format = item
        elif isinstance(item, str):
            out.append(item)
        elif isinstance(item, Location):
            out.append(format_location(item))
        else:
            out.append(format_number(float(item), number_format))
    return "".join(out), newline
