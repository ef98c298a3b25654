"""`twin check REPORT --expect EXPECT.toml [--junit FILE]`: does a run meet expectations?

The expectation file is TOML. Every key is optional; any key not listed here is an
error (a typo must never pass silently). Example::

    [regions]                  # parts per region, at the end of the run
    bin = 100                  # a bare integer: exactly 100
    nest = { max = 1 }         # bounds: { min = N }, { max = N } or { min = N, max = M }

    [parts]
    total = 100                # number of parts in the report
    dropped = 0                # parts that fell (exactly 0)
    unplaced = { max = 2 }     # parts in no region that were not dropped
    region = { bin = [0, 1, 2], nest = [100] }   # where given parts (by id) ended
    pose = [                   # a part's final position, world frame, mm
      { id = 100, position = [300.0, -180.0, 860.0], tolerance_mm = 2.0 },
    ]

    [time]                     # times always take the bounds form
    sim_time_s = { max = 400 }        # simulated time of the run, s
    wall_time_s = { max = 60 }        # wall-clock time of the run, s
    realtime_factor = { min = 10 }    # sim_time_s / wall_time_s
    cycle_time_s = { max = 3.0 }      # mean cycle time, s (see below)
    place_regions = ["bin"]           # regions counted for cycle_time_s (default: all)

    [program]
    errors = 0                 # number of errors the program raised (count or bounds)
    output_contains = ["All done. 100 parts processed"]   # each string must occur
    output_excludes = ["*Undefined value*"]              # none of these may occur

    [cycle_time]               # statistics of the report's cycle_times_s, s (bounds)
    median = { max = 2.0 }     # also mean, min, max and percentiles p<N> (p90, p99.5...)
    p95 = { max = 2.1 }

    [counts]                   # the report's counts (count or bounds), see twin/report.py
    placed = 150               # created, picked, placed, missed, dropped
    missed = 0

    [events]                   # number of events of each kind (count or bounds)
    collision = 0
    dropped = { max = 1 }
    order = ["grasp", "release", { kind = "grasp", part = 1 }]   # occur in this order

Meaning of the figures:

* A region named under ``[regions]`` must exist in the report (the run lists every
  region of the scene, empty ones with 0); an unknown name is a failure that lists
  the report's regions, so ``bni = 100`` cannot slip through.
* ``cycle_time_s`` is the mean of the report's ``cycle_times_s`` when the run
  measured any; otherwise ``sim_time_s`` divided by the number of parts that reached
  a place region (not dropped; region in ``place_regions``, or any region when that
  key is absent). No placed part and no measured cycles is a failure.
* An event kind under ``[events]`` must be one the twin emits (``twin.report.EVENT_KINDS``):
  ``drop`` for ``dropped`` is an error, with the nearest known kind suggested. A kind
  that never occurred counts 0.
* ``[events] order`` lists events (a kind, or ``{ kind, part }``) that must occur in that
  order; other events may come between them.
* ``[parts] pose``: the distance between the part's final position and ``position`` must
  be at most ``tolerance_mm`` (default 1 mm); ``region``: each listed part must end in
  that region. A part id that is not in the report is a failure.
* ``[cycle_time]`` percentiles interpolate linearly between the sorted cycle times (as
  numpy's default); a run with no measured cycle fails every ``[cycle_time]`` check.
* Bounds are inclusive. Counts must be integers; time bounds may be decimals.

Exit status of ``main_check``: 0 when every expectation holds, 1 when any fails
(each failure printed as a sentence), 2 when the report or the expectation file is
missing or invalid, or the expectation file has an unknown key. ``--junit FILE``
also writes a JUnit XML file with one test case per expectation.
"""

from __future__ import annotations

import argparse
import difflib
import math
import re
import statistics
import sys
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from twin.outputs import write_atomically
from twin.report import COUNT_NAMES, EVENT_KINDS, VISION_COUNT_NAMES, Report, ReportError

__all__ = ["check", "evaluate", "load_expect", "main_check", "print_outcomes", "write_junit", "percentile",
           "ExpectError", "Outcome"]


class ExpectError(Exception):
    """An expectation file that is missing, not TOML, or has an unknown/invalid key."""


@dataclass
class Outcome:
    """One expectation and whether it held."""
    section: str
    name: str          # as written, e.g. "bin = 100"
    failure: str | None  # the sentence, or None when it held
    time_s: float = 0.0  # wall-clock time the check took


# --- values -----------------------------------------------------------------

def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


@dataclass
class Bounds:
    exact: float | None = None
    min: float | None = None
    max: float | None = None

    def holds(self, value: float) -> bool:
        if self.exact is not None:
            return value == self.exact
        return ((self.min is None or value >= self.min)
                and (self.max is None or value <= self.max))

    def describe(self, unit: str = "") -> str:
        u = f" {unit}" if unit else ""
        if self.exact is not None:
            return f"exactly {_fmt(self.exact)}{u}"
        if self.min is not None and self.max is not None:
            if self.min == self.max:
                return f"exactly {_fmt(self.min)}{u}"
            return f"between {_fmt(self.min)} and {_fmt(self.max)}{u}"
        if self.min is not None:
            return f"at least {_fmt(self.min)}{u}"
        return f"at most {_fmt(self.max)}{u}"

    def written(self) -> str:
        if self.exact is not None:
            return _fmt(self.exact)
        parts = [f"{k} = {_fmt(v)}" for k, v in (("min", self.min), ("max", self.max)) if v is not None]
        return "{ " + ", ".join(parts) + " }"


def _fmt(v: float) -> str:
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def _bounds(where: str, value: Any, *, integer: bool, allow_bare: bool) -> Bounds:
    """Parse `N` or `{ min = , max = }`; raises ExpectError with the key's location."""
    kind = "an integer" if integer else "a number"
    ok = _is_int if integer else _is_num
    if isinstance(value, dict):
        unknown = sorted(set(value) - {"min", "max"})
        if unknown:
            raise ExpectError(f"{where}: unknown bound {', '.join(repr(u) for u in unknown)} "
                              f"(use min and/or max)")
        if not value:
            raise ExpectError(f"{where}: empty bounds, give min and/or max")
        for k, v in value.items():
            if not ok(v):
                raise ExpectError(f"{where}.{k} must be {kind}, got {v!r}")
        b = Bounds(min=value.get("min"), max=value.get("max"))
        if b.min is not None and b.max is not None and b.min > b.max:
            raise ExpectError(f"{where}: min {b.min} is greater than max {b.max}")
        return b
    if allow_bare and ok(value):
        return Bounds(exact=value)
    if allow_bare:
        raise ExpectError(f"{where} must be {kind} or {{ min = N, max = M }}, got {value!r}")
    raise ExpectError(f"{where} must be written as bounds, e.g. {{ max = 3.0 }}, got {value!r}")


def _strings(where: str, value: Any) -> list[str]:
    if isinstance(value, str):
        return [value]
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return value
    raise ExpectError(f"{where} must be a string or a list of strings, got {value!r}")


def _plural(n: int, one: str, many: str | None = None) -> str:
    return f"{n} {one if n == 1 else (many or one + 's')}"


def _quote(s: str) -> str:
    return repr(s)


# --- expectations -----------------------------------------------------------

Check = tuple[str, str, Callable[[Report], "str | None"]]   # section, name, fn -> failure

SECTIONS = {
    "regions": None,   # free names
    "parts": {"total", "dropped", "unplaced", "region", "pose"},
    "time": {"sim_time_s", "wall_time_s", "realtime_factor", "cycle_time_s", "place_regions"},
    "program": {"errors", "output_contains", "output_excludes"},
    "counts": set(COUNT_NAMES) | set(VISION_COUNT_NAMES),
    "cycle_time": None,   # mean, median, min, max, p<N>: checked by _cycle_statistic
    "events": set(EVENT_KINDS) | {"order"},
}


def _unknown(what: str, name: str, known) -> str:
    """"unknown event kind 'drop' (did you mean 'dropped'?); known: ..." """
    close = difflib.get_close_matches(name, list(known), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    shown = name if what.endswith(":") else repr(name)
    return f"unknown {what} {shown}{hint}; known: {', '.join(sorted(known))}"


def _compile(expect: dict) -> list[Check]:
    """Validate an expectation mapping and turn it into checks (ExpectError if invalid)."""
    if not isinstance(expect, dict):
        raise ExpectError("expectations must be a table")
    unknown = sorted(set(expect) - set(SECTIONS))
    if unknown:
        raise ExpectError(f"unknown section(s) {', '.join('[' + u + ']' for u in unknown)}; "
                          f"known: {', '.join('[' + s + ']' for s in SECTIONS)}")
    for section, keys in SECTIONS.items():
        table = expect.get(section, {})
        if not isinstance(table, dict):
            raise ExpectError(f"[{section}] must be a table")
        if keys is not None:
            for name in table:
                if name not in keys:
                    what = "event kind" if section == "events" else f"key(s) in [{section}]:"
                    raise ExpectError(_unknown(what, name, keys))

    checks: list[Check] = []

    # [regions]
    for name, value in expect.get("regions", {}).items():
        b = _bounds(f"regions.{name}", value, integer=True, allow_bare=True)

        def region(r: Report, name=name, b=b) -> str | None:
            if name not in r.regions:
                known = ", ".join(repr(k) for k in r.regions) or "none"
                return (f"region {name!r} is not in the report (its regions: {known}); "
                        f"expected {b.describe()} parts")
            n = r.regions[name]
            if b.holds(n):
                return None
            return f"region {name!r} holds {_plural(n, 'part')}, expected {b.describe()}"
        checks.append(("regions", f"{name} = {b.written()}", region))

    # [parts]
    parts = expect.get("parts", {})
    part_figures = {
        "total": (lambda r: len(r.parts), "the report lists {n}, expected {b}", "part"),
        "dropped": (lambda r: r.dropped, "{n} dropped, expected {b}", "part"),
        "unplaced": (lambda r: r.unplaced, "{n} in no region (not dropped), expected {b}", "part"),
    }
    for key, value in parts.items():
        if key in ("region", "pose"):
            continue
        b = _bounds(f"parts.{key}", value, integer=True, allow_bare=True)
        get, text, noun = part_figures[key]

        def part_check(r: Report, get=get, text=text, noun=noun, b=b) -> str | None:
            n = get(r)
            if b.holds(n):
                return None
            return text.format(n=_plural(n, noun), b=b.describe())
        checks.append(("parts", f"{key} = {b.written()}", part_check))
    checks += _part_region_checks(parts.get("region", {}))
    checks += _part_pose_checks(parts.get("pose", []))

    # [counts]
    for key, value in expect.get("counts", {}).items():
        b = _bounds(f"counts.{key}", value, integer=True, allow_bare=True)

        def count_check(r: Report, key=key, b=b) -> str | None:
            if r.counts is None:
                return f"the report has no counts (written by a twin without them); expected {key} {b.describe()}"
            n = r.counts[key]
            if b.holds(n):
                return None
            return f"{_plural(n, 'part')} {key}, expected {b.describe()}"
        checks.append(("counts", f"{key} = {b.written()}", count_check))

    # [time]
    time = expect.get("time", {})
    place_regions = None
    if "place_regions" in time:
        place_regions = _strings("time.place_regions", time["place_regions"])
    for key, value in time.items():
        if key == "place_regions":
            continue
        b = _bounds(f"time.{key}", value, integer=False, allow_bare=False)
        if key == "sim_time_s":
            fn = _time_check(lambda r: r.sim_time_s, "simulated time was {v:.3f} s, expected {b}", b, "s")
        elif key == "wall_time_s":
            fn = _time_check(lambda r: r.wall_time_s, "wall-clock time was {v:.3f} s, expected {b}", b, "s")
        elif key == "realtime_factor":
            fn = _realtime_check(b)
        else:
            fn = _cycle_check(b, place_regions)
        checks.append(("time", f"{key} = {b.written()}", fn))

    # [program]
    program = expect.get("program", {})
    if "errors" in program:
        b = _bounds("program.errors", program["errors"], integer=True, allow_bare=True)

        def errors(r: Report, b=b) -> str | None:
            n = len(r.errors)
            if b.holds(n):
                return None
            shown = "; ".join(_describe_error(e) for e in r.errors[:3])
            more = f" (and {n - 3} more)" if n > 3 else ""
            return (f"the program raised {_plural(n, 'error')}, expected {b.describe()}"
                    + (f": {shown}{more}" if shown else ""))
        checks.append(("program", f"errors = {b.written()}", errors))
    for text in _strings("program.output_contains", program.get("output_contains", [])):
        def contains(r: Report, text=text) -> str | None:
            if text in r.output:
                return None
            return f"the program output does not contain {_quote(text)}; {_tail(r.output)}"
        checks.append(("program", f"output contains {_quote(text)}", contains))
    for text in _strings("program.output_excludes", program.get("output_excludes", [])):
        def excludes(r: Report, text=text) -> str | None:
            if text not in r.output:
                return None
            line = next((ln for ln in r.output.splitlines() if text in ln), text)
            return f"the program output contains {_quote(text)}, which it must not (in line {_quote(line)})"
        checks.append(("program", f"output excludes {_quote(text)}", excludes))

    # [cycle_time]
    for key, value in expect.get("cycle_time", {}).items():
        checks.append(_cycle_statistic(key, value))

    # [events]
    events_table = expect.get("events", {})
    if "order" in events_table:
        checks.append(_event_order_check(events_table["order"]))
    for kind, value in events_table.items():
        if kind == "order":
            continue
        b = _bounds(f"events.{kind}", value, integer=True, allow_bare=True)

        def event(r: Report, kind=kind, b=b) -> str | None:
            hits = [e for e in r.events if e.get("kind") == kind]
            if b.holds(len(hits)):
                return None
            first = ""
            if hits and hits[0].get("time") is not None:
                first = f" (first at t = {hits[0]['time']:.3f} s)"
            return f"{_plural(len(hits), repr(kind) + ' event')} occurred, expected {b.describe()}{first}"
        checks.append(("events", f"{kind} = {b.written()}", event))

    return checks


def _part_ids(where: str, value: Any) -> list[int]:
    if isinstance(value, list) and value and all(_is_int(v) for v in value):
        return value
    raise ExpectError(f"{where} must be a non-empty list of part ids (integers), got {value!r}")


def _find_part(r: Report, part_id: int) -> dict | None:
    return next((p for p in r.parts if p["id"] == part_id), None)


def _part_region_checks(table: Any) -> list[Check]:
    """[parts] region = { bin = [0, 1], ... }: each listed part ends in that region."""
    if not isinstance(table, dict):
        raise ExpectError(f"parts.region must be a table of region = [part ids], got {table!r}")
    checks: list[Check] = []
    for region, value in table.items():
        ids = _part_ids(f"parts.region.{region}", value)

        def in_region(r: Report, region=region, ids=ids) -> str | None:
            wrong = []
            for part_id in ids:
                part = _find_part(r, part_id)
                if part is None:
                    wrong.append(f"part {part_id} is not in the report")
                elif part["region"] != region:
                    where = "was dropped" if part["dropped"] else (
                        f"is in {part['region']!r}" if part["region"] else "is in no region")
                    wrong.append(f"part {part_id} {where}")
            if not wrong:
                return None
            return f"expected parts {_id_list(ids)} in region {region!r}: " + "; ".join(wrong)
        checks.append(("parts", f"region {region} = {_id_list(ids)}", in_region))
    return checks


def _id_list(ids: list[int]) -> str:
    return "[" + ", ".join(map(str, ids[:8])) + (", ..." if len(ids) > 8 else "") + "]"


POSE_KEYS = {"id", "position", "tolerance_mm"}


def _part_pose_checks(items: Any) -> list[Check]:
    """[parts] pose = [{ id, position = [x, y, z] mm, tolerance_mm }]: a part's final position."""
    if isinstance(items, dict):
        items = [items]
    if not isinstance(items, list):
        raise ExpectError(f"parts.pose must be a list of {{ id, position, tolerance_mm }} tables, got {items!r}")
    checks: list[Check] = []
    for n, item in enumerate(items):
        where = f"parts.pose[{n}]"
        if not isinstance(item, dict):
            raise ExpectError(f"{where} must be a table {{ id, position, tolerance_mm }}, got {item!r}")
        for key in item:
            if key not in POSE_KEYS:
                raise ExpectError(f"{where}: " + _unknown("key", key, POSE_KEYS))
        part_id, position = item.get("id"), item.get("position")
        tolerance = item.get("tolerance_mm", 1.0)
        if not _is_int(part_id):
            raise ExpectError(f"{where}.id must be a part id (integer), got {part_id!r}")
        if not (isinstance(position, list) and len(position) == 3 and all(_is_num(v) for v in position)):
            raise ExpectError(f"{where}.position must be [x, y, z] in mm, got {position!r}")
        if not _is_num(tolerance) or tolerance < 0:
            raise ExpectError(f"{where}.tolerance_mm must be a number >= 0, got {tolerance!r}")

        def pose(r: Report, part_id=part_id, position=position, tolerance=tolerance) -> str | None:
            part = _find_part(r, part_id)
            if part is None:
                return f"part {part_id} is not in the report (it has {len(r.parts)} parts)"
            actual = part["pose"][:3]
            distance = math.dist(actual, position)
            if distance <= tolerance:
                return None
            return (f"part {part_id} is {distance:.1f} mm from {_xyz(position)} (it is at {_xyz(actual)}"
                    f"{', dropped' if part['dropped'] else ''}), expected within {_fmt(tolerance)} mm")
        checks.append(("parts", f"pose of part {part_id} within {_fmt(tolerance)} mm of {_xyz(position)}", pose))
    return checks


def _xyz(v: list[float]) -> str:
    return "(" + ", ".join(f"{x:.1f}" for x in v) + ") mm"


_STATISTIC = re.compile(r"^(mean|median|min|max|p(\d{1,2}(\.\d+)?|100))$")


def percentile(values: list[float], q: float) -> float:
    """The q-th percentile (0-100), linear between the sorted values (numpy's default)."""
    ordered = sorted(values)
    rank = (len(ordered) - 1) * q / 100.0
    low = math.floor(rank)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (rank - low)


def _cycle_statistic(key: str, value: Any) -> Check:
    """[cycle_time] mean/median/min/max/p<N> = { min, max }: over the measured cycle times."""
    if not _STATISTIC.match(key):
        raise ExpectError(_unknown("key(s) in [cycle_time]:", key, ["mean", "median", "min", "max", "p50", "p95", "p99"])
                          + " (or any percentile p<N>, 0 < N <= 100)")
    b = _bounds(f"cycle_time.{key}", value, integer=False, allow_bare=False)
    compute = {"mean": statistics.fmean, "median": statistics.median, "min": min, "max": max}.get(key)
    if compute is None:
        q = float(key[1:])
        compute = lambda values, q=q: percentile(values, q)   # noqa: E731

    def fn(r: Report) -> str | None:
        if not r.cycle_times_s:
            return f"cycle time {key} is undefined: the run measured no cycle"
        v = compute(r.cycle_times_s)
        if b.holds(v):
            return None
        return (f"cycle time {key} was {v:.3f} s (over {_plural(len(r.cycle_times_s), 'cycle')}), "
                f"expected {b.describe('s')}")
    return ("cycle_time", f"{key} = {b.written()}", fn)


def _event_order_check(items: Any) -> Check:
    """[events] order = ["grasp", { kind = "release", part = 0 }, ...]: a subsequence of the events."""
    if not isinstance(items, list) or not items:
        raise ExpectError(f"events.order must be a non-empty list of event kinds or {{ kind, part }} tables, "
                          f"got {items!r}")
    wanted: list[tuple[str, int | None]] = []
    for n, item in enumerate(items):
        where = f"events.order[{n}]"
        kind, part = (item, None) if isinstance(item, str) else (
            (item.get("kind"), item.get("part")) if isinstance(item, dict) else (None, None))
        if isinstance(item, dict):
            for key in item:
                if key not in ("kind", "part"):
                    raise ExpectError(f"{where}: " + _unknown("key", key, ["kind", "part"]))
        if not isinstance(kind, str):
            raise ExpectError(f"{where} must be an event kind or {{ kind, part }}, got {item!r}")
        if kind not in EVENT_KINDS:
            raise ExpectError(f"{where}: " + _unknown("event kind", kind, EVENT_KINDS))
        if part is not None and not _is_int(part):
            raise ExpectError(f"{where}.part must be a part id (integer), got {part!r}")
        wanted.append((kind, part))

    def label(kind: str, part: int | None) -> str:
        return kind if part is None else f"{kind} of part {part}"

    def fn(r: Report) -> str | None:
        i = 0
        last_time = None
        for event in r.events:
            kind, part = wanted[i]
            if event.get("kind") == kind and (part is None or event.get("part") == part):
                i, last_time = i + 1, event.get("time")
                if i == len(wanted):
                    return None
        after = "" if i == 0 else f" after {label(*wanted[i - 1])}" + (
            f" at t = {last_time:.3f} s" if last_time is not None else "")
        return f"events out of order: no {label(*wanted[i])}{after} (event {i + 1} of {len(wanted)} in the order)"
    return ("events", "order " + ", ".join(label(*w) for w in wanted), fn)


def _time_check(get, text, b: Bounds, unit: str):
    def fn(r: Report) -> str | None:
        v = get(r)
        return None if b.holds(v) else text.format(v=v, b=b.describe(unit))
    return fn


def _realtime_check(b: Bounds):
    def fn(r: Report) -> str | None:
        if r.wall_time_s <= 0:
            return "real-time factor is undefined: wall_time_s is 0"
        v = r.sim_time_s / r.wall_time_s
        if b.holds(v):
            return None
        return (f"the run went {v:.2f}x real time ({r.sim_time_s:.3f} s simulated in "
                f"{r.wall_time_s:.3f} s), expected {b.describe('x')}")
    return fn


def _cycle_check(b: Bounds, place_regions: list[str] | None):
    def fn(r: Report) -> str | None:
        if r.cycle_times_s:
            v = sum(r.cycle_times_s) / len(r.cycle_times_s)
            how = f"mean of {_plural(len(r.cycle_times_s), 'measured cycle')}"
        else:
            placed = sum(1 for p in r.parts if not p["dropped"] and p["region"] is not None
                         and (place_regions is None or p["region"] in place_regions))
            where = ("a place region" if place_regions is None
                     else "region " + " or ".join(repr(x) for x in place_regions))
            if placed == 0:
                return f"cycle time is undefined: no part reached {where} and no cycle was measured"
            v = r.sim_time_s / placed
            how = f"{r.sim_time_s:.3f} s / {_plural(placed, 'part')} in {where}"
        if b.holds(v):
            return None
        return f"cycle time was {v:.3f} s ({how}), expected {b.describe('s')}"
    return fn


def _describe_error(e: dict) -> str:
    where = ""
    if e.get("file"):
        where = e["file"] + (f":{e['line']}" if e.get("line") is not None else "") + ": "
    code = f" ({e['code']})" if e.get("code") is not None else ""
    return f"{where}{e.get('message', '')}{code}"


def _tail(output: str, lines: int = 3) -> str:
    if not output:
        return "the program typed nothing"
    last = output.rstrip("\n").splitlines()[-lines:]
    return "its last lines were: " + " | ".join(last)


# --- API --------------------------------------------------------------------

def load_expect(path: str | Path) -> dict:
    """Read an expectation file; raises ExpectError on a missing file or bad TOML."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            data = tomllib.load(f)
    except FileNotFoundError:
        raise ExpectError(f"{path}: no such expectation file") from None
    except IsADirectoryError:
        raise ExpectError(f"{path}: is a directory, not an expectation file") from None
    except OSError as e:
        raise ExpectError(f"{path}: cannot read: {e}") from None
    except tomllib.TOMLDecodeError as e:
        raise ExpectError(f"{path}: not valid TOML: {e}") from None
    except UnicodeDecodeError as e:  # TOML is UTF-8 text
        raise ExpectError(f"{path}: not valid TOML: not UTF-8 text ({e.reason} at byte {e.start})") from None
    try:
        _compile(data)
    except ExpectError as e:
        raise ExpectError(f"{path}: {e}") from None
    return data


def evaluate(report: Report, expect: dict) -> list[Outcome]:
    """Every expectation with its outcome, in file order (ExpectError if `expect` is invalid)."""
    outcomes = []
    for section, name, fn in _compile(expect):
        start = time.perf_counter()
        failure = fn(report)
        outcomes.append(Outcome(section, name, failure, time.perf_counter() - start))
    return outcomes


def check(report: Report, expect: dict) -> list[str]:
    """The failures, one sentence each; empty when every expectation holds.

    Raises ExpectError when `expect` has an unknown key or an invalid value."""
    return [o.failure for o in evaluate(report, expect) if o.failure is not None]


def write_junit(path: str | Path, outcomes: list[Outcome], *, suite: str = "twin check",
                error: str | None = None, report: Report | None = None) -> None:
    """JUnit XML: one testcase per expectation; `error` alone records a load error.

    With the `report`, the suite carries the run's wall-clock time as its time and the
    run's program, scene, seed, simulated time (and interruption) as properties."""
    suite_el = ET.Element("testsuite", name=suite)
    if report is not None:
        suite_el.set("time", f"{report.wall_time_s:.3f}")
        props = ET.SubElement(suite_el, "properties")
        for key in ("program", "scene", "seed", "sim_time_s", "wall_time_s", "interrupted"):
            if hasattr(report, key):
                ET.SubElement(props, "property", name=key, value=str(getattr(report, key)))
    failures = 0
    if error is not None:
        case = ET.SubElement(suite_el, "testcase", classname="twin.check", name="load")
        ET.SubElement(case, "error", message=error).text = error
    for o in outcomes:
        case = ET.SubElement(suite_el, "testcase", classname=f"twin.check.{o.section}", name=o.name,
                             time=f"{o.time_s:.6f}")
        if o.failure is not None:
            failures += 1
            ET.SubElement(case, "failure", message=o.failure).text = o.failure
    suite_el.set("tests", str(len(outcomes) + (error is not None)))
    suite_el.set("failures", str(failures))
    suite_el.set("errors", str(int(error is not None)))
    root = ET.Element("testsuites")
    root.append(suite_el)
    ET.indent(root)
    write_atomically(path, ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n")


def build_parser(prog: str = "twin check") -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=prog, description="Check a run's placement report against expectations.")
    p.add_argument("report", help="report JSON written by `twin run --report`")
    p.add_argument("--expect", required=True, metavar="EXPECT.toml", help="expectation file (TOML)")
    p.add_argument("--junit", metavar="FILE", help="also write a JUnit XML file")
    return p


def main_check(argv: list[str] | None = None) -> int:
    """Command line entry: 0 all hold, 1 some fail, 2 bad input. Never a traceback."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:   # argparse printed the usage and reason
        return 0 if e.code == 0 else 2
    try:
        expect = load_expect(args.expect)
        report = Report.load(args.report)
        outcomes = evaluate(report, expect)
    except (ExpectError, ReportError) as e:
        print(f"twin check: error: {e}", file=sys.stderr)
        if args.junit:
            _safe_junit(args.junit, [], error=str(e))
        return 2
    if args.junit:
        if not _safe_junit(args.junit, outcomes, report=report):
            return 2
    return print_outcomes(outcomes, args.report)


def print_outcomes(outcomes: list[Outcome], source: str) -> int:
    """The verdict on standard output; 0 when all hold, 1 otherwise."""
    failed = [o for o in outcomes if o.failure is not None]
    if failed:
        print(f"FAILED: {len(failed)} of {len(outcomes)} expectations for {source}:")
        for o in failed:
            print(f"  - {o.failure}")
        return 1
    print(f"OK: all {len(outcomes)} expectations hold for {source}")
    return 0


def _safe_junit(path: str, outcomes: list[Outcome], error: str | None = None,
                report: Report | None = None) -> bool:
    try:
        write_junit(path, outcomes, error=error, report=report)
        return True
    except OSError as e:
        print(f"twin check: error: cannot write JUnit file {path}: {e}", file=sys.stderr)
        return False


if __name__ == "__main__":
    sys.exit(main_check())
