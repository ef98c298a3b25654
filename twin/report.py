"""The placement report written after a run, as JSON.

One file per run; CI checks it against an expectation file (`twin.check`).

Layout (``Report.to_json``)::

    {
      "twin_report": 1,                 # format version
      "program": "programs/vplus/move_parts.pg",
      "scene": "scenes/scara_pick.toml",
      "seed": 0,
      "sim_time_s": 312.4,              # simulated time
      "wall_time_s": 21.9,              # wall-clock time of the run
      "output": "...",                  # everything the program TYPEd, exactly
      "errors": [ {"code": -413, "message": "*Undefined value*",
                   "file": "move_parts.pg", "line": 12, "column": 5, "time": 3.2} ],
      "parts": [ {"id": 0, "type": "block", "pose": [x, y, z, qw, qx, qy, qz], "region": "tray",
                  "dropped": false, "picked": true, "missed": false, "tray": "tray", "cell": 3} ],
      "regions": {"bin": 100, "nest": 0},
      "counts": {"created": 101, "picked": 100, "placed": 100, "missed": 0, "dropped": 0},
      "components": {"conveyor.infeed": {"speed_mm_s": 100.0, "travel_mm": 30000.0, ...}},
      "events": [ {"time": 12.5, "kind": "drop", ...free fields...} ],
      "cycle_times_s": [0.61, 0.58],
      "interrupted": false              # true when Ctrl-C / SIGTERM stopped the run early
    }

The JSON Schema of this layout is twin/schemas/report.schema.json (docs/ci.md).

Units: part positions in millimetres (as the controller reports them), orientation
as a unit quaternion in MuJoCo's order (w, x, y, z); times in seconds of simulated
time unless the key says ``wall``.

Regions: ``regions`` maps a region name to the number of parts whose ``region`` is
that name. It is derived from ``parts``: a part in no region (``"region": null``)
is not counted anywhere (JSON object keys cannot be null); ``twin check`` exposes
those as ``[parts] unplaced``. The writer should list every region the scene
declares, with 0 for an empty one, so that an expectation naming a region the
scene does not have is reported as a typo rather than silently read as 0.
Pass ``regions=None`` (the default) to derive the counts from ``parts``; extra
names with a count of 0 may be given, and any other disagreement with ``parts``
is an error.

Parts: one entry per part instance the cell brought in (a feeder's present, a source's
spawn), in order; ``id`` is the instance's number (a pooled body that comes back is a new
instance). Required keys: ``id``, ``pose``, ``region`` (where it ended, or where it was
when its body was taken back), ``dropped`` (fell or was let go outside a place region).
Optional: ``type`` (the scene's part type), ``picked`` (a gripper held it at least once),
``missed`` (it left a conveyor, or a program's window, without being picked), ``tray`` and
``cell`` (the tray's name and the 0-based cell index, row * cols + col, when it lies in
a tray cell).

Counts: ``counts`` (optional; the cell writes it) has ``created`` (parts brought in),
``picked``, ``placed`` (ended in a place region, neither dropped nor missed), ``missed``
and ``dropped``: non-negative integers, checkable as ``[counts]`` in an expectation file.
A vision cell adds ``located``, ``not_found`` and ``rejected`` (what the vision server told
the programs: docs/vision.md).
``components`` (optional) holds each cell component's own figures, keyed
``<kind>.<name>`` (free fields: a conveyor's speed, travel and encoder count, a sensor's
breaks, a tray's cell centres...).

Events: each event is an object with at least ``time`` (seconds, may be null)
and ``kind`` (a short word: "drop", "collision", "grasp", ...); other fields are
free.
"""

from __future__ import annotations

import json
import math
import os
from collections import Counter
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

from .outputs import write_atomically

FORMAT_VERSION = 1

__all__ = ["Report", "ReportError", "count_regions", "COUNT_NAMES", "EVENT_KINDS", "VISION_COUNT_NAMES", "FORMAT_VERSION"]

# Every kind of cell event a run reports (twin.physics and its components); `twin check` rejects any other
# name, and tests/test_ci_tooling.py keeps this list and the cell in step.
EVENT_KINDS = ("present", "spawn", "grasp", "release", "slip", "overload", "missed", "dropped", "collision",
               "feeder_empty", "source_empty", "tray_swapped")


class ReportError(Exception):
    """A report file that is missing, unreadable or not a valid report."""


def count_regions(parts: list[dict]) -> dict[str, int]:
    """Parts per region name; parts with no region are not counted."""
    counts = Counter(p.get("region") for p in parts)
    counts.pop(None, None)
    return dict(sorted(counts.items()))


_PART_REQUIRED = {"id", "pose", "region", "dropped"}
_PART_OPTIONAL = {"type": (str,), "picked": (bool,), "missed": (bool,), "tray": (str,), "cell": (int,)}
COUNT_NAMES = ("created", "picked", "placed", "missed", "dropped")
VISION_COUNT_NAMES = ("located", "not_found", "rejected")  # in a cell with [vision] (docs/vision.md)

_ERROR_KEYS = {"code": (int, type(None)), "message": (str,), "file": (str, type(None)),
               "line": (int, type(None)), "column": (int, type(None)),
               "text": (str, type(None)), "step": (int, type(None)), "program": (str, type(None)),
               "time": (int, float, type(None))}


@dataclass
class Report:
    program: str
    scene: str
    seed: int
    sim_time_s: float
    wall_time_s: float
    output: str
    errors: list[dict] = field(default_factory=list)
    parts: list[dict] = field(default_factory=list)
    regions: dict[str, int] | None = None
    events: list[dict] = field(default_factory=list)
    cycle_times_s: list[float] = field(default_factory=list)
    counts: dict[str, int] | None = None
    components: dict[str, dict] = field(default_factory=dict)
    interrupted: bool = False

    def __post_init__(self) -> None:
        _validate(self)
        derived = count_regions(self.parts)
        if self.regions is None:
            self.regions = derived
        else:
            for name in set(derived) | set(self.regions):
                if self.regions.get(name, 0) != derived.get(name, 0):
                    raise ReportError(
                        f"regions[{name!r}] = {self.regions.get(name, 0)} but "
                        f"{derived.get(name, 0)} part(s) list region {name!r}")
            self.regions = dict(sorted({**self.regions, **derived}.items()))

    # Convenience figures used by the checker.
    @property
    def dropped(self) -> int:
        return sum(1 for p in self.parts if p["dropped"])

    @property
    def unplaced(self) -> int:
        """Parts that are in no region and were not dropped."""
        return sum(1 for p in self.parts if p["region"] is None and not p["dropped"])

    def to_json(self) -> str:
        body = {"twin_report": FORMAT_VERSION, **asdict(self)}
        try:
            return json.dumps(body, indent=2, allow_nan=False) + "\n"
        except ValueError:
            bad = _first_non_finite(body)
            raise ValueError(f"report value {bad} is not a finite number") from None

    def write(self, path: str | os.PathLike) -> None:
        """Write atomically (a reader never sees half a report), only over a regular file."""
        write_atomically(path, self.to_json())

    @classmethod
    def from_dict(cls, data: Any, source: str = "report") -> "Report":
        if not isinstance(data, dict):
            raise ReportError(f"{source}: expected a JSON object, got {type(data).__name__}")
        data = dict(data)
        version = data.pop("twin_report", FORMAT_VERSION)
        if version != FORMAT_VERSION:
            raise ReportError(f"{source}: report format {version!r} is not supported "
                              f"(this twin reads format {FORMAT_VERSION})")
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(data) - set(names))
        if unknown:
            raise ReportError(f"{source}: unknown key(s) {', '.join(unknown)}")
        required = ["program", "scene", "seed", "sim_time_s", "wall_time_s", "output"]
        missing = [k for k in required if k not in data]
        if missing:
            raise ReportError(f"{source}: missing key(s) {', '.join(missing)}")
        try:
            return cls(**data)
        except ReportError as e:
            raise ReportError(f"{source}: {e}") from None
        except (TypeError, ValueError, KeyError, AttributeError) as e:
            raise ReportError(f"{source}: invalid report: {e}") from None

    @classmethod
    def load(cls, path: str | os.PathLike) -> "Report":
        """Read a report; raises ReportError with a one-line reason on any problem."""
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise ReportError(f"{path}: no such report file") from None
        except IsADirectoryError:
            raise ReportError(f"{path}: is a directory, not a report file") from None
        except (OSError, UnicodeDecodeError) as e:
            raise ReportError(f"{path}: cannot read report: {e}") from None
        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise ReportError(f"{path}: not valid JSON (line {e.lineno}, column {e.colno}: {e.msg})") from None
        return cls.from_dict(data, source=str(path))


def _is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _validate(r: Report) -> None:
    def need(cond: bool, what: str) -> None:
        if not cond:
            raise ReportError(what)

    need(isinstance(r.program, str), "program must be a string")
    need(isinstance(r.scene, str), "scene must be a string")
    need(isinstance(r.seed, int) and not isinstance(r.seed, bool), "seed must be an integer")
    need(_is_num(r.sim_time_s), "sim_time_s must be a number")
    need(_is_num(r.wall_time_s), "wall_time_s must be a number")
    need(isinstance(r.output, str), "output must be a string")
    need(isinstance(r.errors, list), "errors must be a list")
    for i, e in enumerate(r.errors):
        need(isinstance(e, dict), f"errors[{i}] must be an object")
        need("message" in e, f"errors[{i}] has no message")
        for key, value in e.items():
            need(key in _ERROR_KEYS, f"errors[{i}] has unknown key {key!r}")
            need(isinstance(value, _ERROR_KEYS[key]) and not isinstance(value, bool),
                 f"errors[{i}].{key} has the wrong type ({value!r})")
        for key in _ERROR_KEYS:
            e.setdefault(key, None)
    need(isinstance(r.parts, list), "parts must be a list")
    for i, p in enumerate(r.parts):
        need(isinstance(p, dict), f"parts[{i}] must be an object")
        need(_PART_REQUIRED <= set(p) <= _PART_REQUIRED | set(_PART_OPTIONAL),
             f"parts[{i}] must have the keys id, pose, region, dropped and may have "
             f"{', '.join(_PART_OPTIONAL)} (has {', '.join(sorted(p))})")
        for key, types in _PART_OPTIONAL.items():
            need(key not in p or (isinstance(p[key], types) and (bool in types or not isinstance(p[key], bool))),
                 f"parts[{i}].{key} has the wrong type ({p.get(key)!r})")
        need(isinstance(p["id"], int) and not isinstance(p["id"], bool), f"parts[{i}].id must be an integer")
        need(isinstance(p["pose"], list) and len(p["pose"]) == 7 and all(_is_num(v) for v in p["pose"]),
             f"parts[{i}].pose must be 7 numbers [x, y, z (mm), qw, qx, qy, qz]")
        need(p["region"] is None or isinstance(p["region"], str), f"parts[{i}].region must be a string or null")
        need(isinstance(p["dropped"], bool), f"parts[{i}].dropped must be true or false")
    ids = [p["id"] for p in r.parts]
    need(len(ids) == len(set(ids)), "part ids are not unique")
    if r.regions is not None:
        need(isinstance(r.regions, dict) and all(
            isinstance(k, str) and isinstance(v, int) and not isinstance(v, bool) and v >= 0
            for k, v in r.regions.items()), "regions must map names to part counts")
    if r.counts is not None:
        need(isinstance(r.counts, dict) and set(COUNT_NAMES) <= set(r.counts) and all(
            isinstance(k, str) and isinstance(v, int) and not isinstance(v, bool) and v >= 0
            for k, v in r.counts.items()), f"counts must map at least {', '.join(COUNT_NAMES)} to part counts")
    need(isinstance(r.components, dict) and all(isinstance(v, dict) for v in r.components.values()),
         "components must map names to objects")
    need(isinstance(r.events, list), "events must be a list")
    for i, ev in enumerate(r.events):
        need(isinstance(ev, dict) and isinstance(ev.get("kind"), str),
             f"events[{i}] must be an object with a string 'kind'")
        need(ev.get("time") is None or _is_num(ev.get("time")), f"events[{i}].time must be a number or null")
    need(isinstance(r.cycle_times_s, list) and all(_is_num(v) for v in r.cycle_times_s),
         "cycle_times_s must be a list of numbers")
    need(isinstance(r.interrupted, bool), "interrupted must be true or false")


def _first_non_finite(obj: Any, where: str = "") -> str:
    if isinstance(obj, float) and not math.isfinite(obj):
        return f"{where or '<root>'} = {obj}"
    if isinstance(obj, dict):
        items = obj.items()
    elif isinstance(obj, (list, tuple)):
        items = enumerate(obj)
    else:
        return ""
    for k, v in items:
        found = _first_non_finite(v, f"{where}[{k!r}]" if where else str(k))
        if found:
            return found
    return ""
