"""Vision processes: the named sequences of tools a cell file defines, one per job.

    [vision]
    time_s = 0.08                 # simulated processing time of one process run
    [[vision.process]]
    name = "Main"                 # what the program asks for (GPL Process "Main"; V+ sequence 1)
    camera = "top"
    plane_z = 8.0                 # mm, robot frame: the height of the faces the tools measure
    area = [150.0, -330.0, 450.0, -70.0]   # robot x, y lo and hi, mm: the part of the picture used
    scale = 0.25                  # mm per pixel of the metric view
    latch_encoder = 1             # optional: each picture latches this belt encoder (a strobe)
      [[vision.process.tool]]
      name = "blobs"
      type = "blob"               # blob | pattern | inspection (parameters: locators.py)
      threshold = 170

Tool 1 of a process is the image acquisition (as in AdeptSight and PreciseVision, where a
process starts with its acquisition tool); the tools of the file are tools 2, 3, ... in
order.  A pattern tool with ``near = "<tool>"`` searches around each instance of that
tool; an inspection names its ``source`` tool and ``checks`` = [[property, min, max], ...].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import cv2
import numpy as np

from .calibration import CameraModel
from .locators import BlobLocator, Inspection, Instance, PatternLocator
from .view import PlaneView

ACQUIRE = "acquire"  # the name of every process's first tool

# What a process's tools see of the colour picture (a colour filter, as on a colour camera).
CHANNELS = {
    "gray": lambda rgb: cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY),
    "red": lambda rgb: np.ascontiguousarray(rgb[..., 0]),
    "green": lambda rgb: np.ascontiguousarray(rgb[..., 1]),
    "blue": lambda rgb: np.ascontiguousarray(rgb[..., 2]),
    "saturation": lambda rgb: np.ascontiguousarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)[..., 1]),
    "value": lambda rgb: np.ascontiguousarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)[..., 2]),
}

TOOL_TYPES = {"blob": BlobLocator, "pattern": PatternLocator}


@dataclass
class MultiInspection:
    """Every check of an instance must hold; ``actual`` is the value of the first check
    that failed (of the first check when all hold)."""

    source: str
    checks: list[Inspection]

    def run(self, instances: list[Instance]) -> list[Instance]:
        out = []
        for inst in instances:
            results = [check.run([inst])[0] for check in self.checks]
            failed = [r for r in results if not r.passed]
            chosen = failed[0] if failed else results[0]
            out.append(Instance(**{**inst.__dict__, "passed": not failed, "actual": chosen.actual}))
        return out


@dataclass
class Tool:
    name: str
    kind: str  # acquire | blob | pattern | inspection
    impl: object = None
    near: str | None = None  # pattern: search around this tool's instances

    def parameters(self) -> dict[str, object]:
        """The tool's settable properties (GPL ToolProperty, V+ VPARAMETER)."""
        if self.impl is None or self.kind == "inspection":
            return {}
        return {f.name: getattr(self.impl, f.name) for f in fields(self.impl)
                if not f.name.startswith("_") and isinstance(getattr(self.impl, f.name), (int, float, str, bool))}

    def set_parameter(self, name: str, value) -> None:
        params = self.parameters()
        if name not in params:
            raise KeyError(f"tool {self.name!r} has no property {name!r} (has: {', '.join(params) or 'none'})")
        old = params[name]
        setattr(self.impl, name, type(old)(value) if not isinstance(old, bool) else bool(value))


def _tool(process: str, table: dict) -> Tool:
    table = dict(table)
    where = f"vision process {process!r} tool {table.get('name', '?')!r}"
    try:
        name, kind = table.pop("name"), table.pop("type")
    except KeyError as missing:
        raise ValueError(f"{where}: needs {missing}") from None
    if kind == "inspection":
        source = table.pop("source", None)
        checks = table.pop("checks", None)
        if source is None or not checks or table:
            raise ValueError(f"{where}: an inspection takes source and checks = [[property, min, max], ...]"
                             + (f" (unknown: {', '.join(table)})" if table else ""))
        return Tool(name, kind, MultiInspection(source, [Inspection(source, str(p), float(lo), float(hi))
                                                          for p, lo, hi in checks]))
    if kind not in TOOL_TYPES:
        raise ValueError(f"{where}: type {kind!r} is not blob, pattern or inspection")
    near = table.pop("near", None) if kind == "pattern" else None
    cls = TOOL_TYPES[kind]
    known = {f.name for f in fields(cls) if not f.name.startswith("_")}
    unknown = sorted(set(table) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}; expected {', '.join(sorted(known))}")
    if kind == "pattern":
        table.setdefault("name", name)
    return Tool(name, kind, cls(**table), near)


@dataclass
class Process:
    name: str
    camera: str
    plane_z: float
    area: tuple[float, float, float, float]
    scale: float = 0.25
    channel: str = "gray"  # what the tools see: gray, red, green, blue, saturation, value
    latch_encoder: int | None = None  # the camera's strobe latches this belt encoder at each picture
    tools: list[Tool] = field(default_factory=list)  # tools[0] is the acquisition
    _view: PlaneView | None = field(default=None, repr=False)

    @classmethod
    def from_table(cls, table: dict) -> "Process":
        table = dict(table)
        name = table.get("name", "?")
        tools = [Tool(ACQUIRE, "acquire")] + [_tool(name, t) for t in table.pop("tool", [])]
        known = {"name", "camera", "plane_z", "area", "scale", "channel", "latch_encoder"}
        unknown = sorted(set(table) - known)
        missing = sorted({"name", "camera", "plane_z", "area"} - set(table))
        if unknown or missing:
            raise ValueError(f"vision process {name!r}: " + "; ".join(
                ([f"unknown key(s) {', '.join(unknown)}"] if unknown else [])
                + ([f"missing {', '.join(missing)}"] if missing else [])))
        names = [t.name for t in tools]
        if len(set(names)) != len(names):
            raise ValueError(f"vision process {name!r}: two tools share a name ({names})")
        for t in tools:
            ref = t.near if t.kind == "pattern" else getattr(t.impl, "source", None)
            if ref is not None and ref not in names[:names.index(t.name)]:
                raise ValueError(f"vision process {name!r} tool {t.name!r}: {ref!r} is not an earlier tool")
        channel = str(table.get("channel", "gray"))
        if channel not in CHANNELS:
            raise ValueError(f"vision process {name!r}: channel {channel!r} is not one of {', '.join(CHANNELS)}")
        latch = table.get("latch_encoder")
        if latch is not None and (isinstance(latch, bool) or not isinstance(latch, int)):
            raise ValueError(f"vision process {name!r}: latch_encoder is a belt encoder number, got {latch!r}")
        return cls(name=name, camera=table["camera"], plane_z=float(table["plane_z"]),
                   area=tuple(float(v) for v in table["area"]), scale=float(table.get("scale", 0.25)),
                   channel=channel, latch_encoder=latch, tools=tools)

    def tool(self, name: str) -> Tool:
        if not str(name) and self.tools:  # no name: the default result, the process's last tool
            return self.tools[-1]
        for t in self.tools:
            if t.name.lower() == str(name).lower():
                return t
        raise KeyError(f"process {self.name!r} has no tool {name!r} (has: {', '.join(t.name for t in self.tools)})")

    def view(self, camera: CameraModel) -> PlaneView:
        if self._view is None or self._view.camera is not camera:
            x0, y0, x1, y1 = self.area
            self._view = PlaneView(camera, self.plane_z, (x0, y0), (x1, y1), self.scale)
        return self._view

    def run(self, rgb: np.ndarray, camera: CameraModel) -> tuple[np.ndarray, dict[str, list[Instance]]]:
        """The tools on one picture: the metric view and each tool's instances."""
        view = self.view(camera)
        image = view.resample(CHANNELS[self.channel](rgb))
        results: dict[str, list[Instance]] = {ACQUIRE: []}
        for t in self.tools[1:]:
            if t.kind == "blob":
                results[t.name] = t.impl.run(view, image)
            elif t.kind == "pattern":
                results[t.name] = t.impl.run(view, image, near=results[t.near] if t.near else None)
            else:
                results[t.name] = t.impl.run(results[t.impl.source])
        return image, results


def processes_of(scene: dict) -> tuple[list[Process], float]:
    """The processes of a cell file's [vision] section and the processing time (s)."""
    vision = dict(scene.get("vision", {}))
    time_s = float(vision.pop("time_s", 0.08))
    tables = vision.pop("process", [])
    vision.pop("address", None)
    if vision:
        raise ValueError(f"[vision]: unknown key(s) {', '.join(sorted(vision))}; expected time_s, address, process")
    procs = [Process.from_table(t) for t in tables]
    names = [p.name.lower() for p in procs]
    if len(set(names)) != len(names):
        raise ValueError("[vision]: two processes share a name")
    if not math.isfinite(time_s) or time_s < 0:
        raise ValueError("[vision] time_s must be a time in seconds, 0 or more")
    return procs, time_s
