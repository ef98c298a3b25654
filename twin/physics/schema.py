"""The scene file's schema (pydantic v2): every section, key, type and bound a scene may use.

`validate_scene(raw, path)` turns the parsed TOML into a `Scene` or raises `SceneError`
(a user error: `twin run` prints it and exits 2) naming the file, the key path and what
was expected, e.g.::

    scenes/x.toml: conveyor[0].speed: expected a number, got 'fast'
    scenes/x.toml: unknown section [convayor] (known: bin, conveyor, ...; did you mean conveyor?)

Rules (docs/scene.md): no unknown section or key at any level; numbers must be finite
(no nan/inf); lengths that size something must be positive; direction vectors non-zero;
names unique per kind; cross references (the robot's home location, a source's or a
sensor's conveyor, a part type, an encoder a photo-eye latches) must exist.
Units in the file: mm, degrees, kg, mm/s, s; world poses for cell objects, robot-base
frame for taught locations.
"""

from __future__ import annotations

import difflib
import math
import types
from pathlib import Path
from typing import Annotated, Any, Literal, Union, get_args, get_origin

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from ..errors import SceneError

# No number in a cell is near a million in the file's units (mm, deg, kg, mm/s, s): larger
# ones are typos (1e300) that would overflow the physics.
HUGE = 1e6
Finite = Annotated[float, Field(ge=-HUGE, le=HUGE, allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, le=HUGE, allow_inf_nan=False)]
NonNegative = Annotated[float, Field(ge=0, le=HUGE, allow_inf_nan=False)]
Vec2 = Annotated[list[Finite], Field(min_length=2, max_length=2)]
Vec3 = Annotated[list[Finite], Field(min_length=3, max_length=3)]
Size2 = Annotated[list[Positive], Field(min_length=2, max_length=2)]
Size3 = Annotated[list[Positive], Field(min_length=3, max_length=3)]
Pose6 = Annotated[list[Finite], Field(min_length=6, max_length=6)]
Rgba = Annotated[list[Annotated[float, Field(ge=0, le=1)]], Field(min_length=4, max_length=4)]
Seed = Annotated[int, Field(ge=0, le=2**63 - 1)]  # numpy's random seeds are non-negative
Output = Annotated[int, Field(ge=1, le=512)]  # V+ digital outputs
Input = Annotated[int, Field(ge=1001, le=1512)]  # V+ digital inputs


class Section(BaseModel):
    """Base of every table: unknown keys are errors, ints are accepted for floats only."""
    model_config = ConfigDict(extra="forbid", strict=True)


def _nonzero(v: list[float]) -> list[float]:
    if math.hypot(*v) < 1e-9:
        raise ValueError("direction must not be the zero vector")
    return v


class Physics(Section):
    timestep: Annotated[float, Field(gt=0, le=0.1, allow_inf_nan=False)] = 0.002  # s
    integrator: Literal["implicitfast", "implicit", "euler", "rk4"] = "implicitfast"
    sleep: bool = True
    # s; the controller's major cycle: programs see a check's results (signals, events) only
    # at the next cycle, so checking more often changes nothing they can observe
    check_interval: Annotated[float, Field(gt=0, le=10.0, allow_inf_nan=False)] = 0.016
    seed: Seed = 0


class Controller(Section):
    monitor_speed: Annotated[float, Field(gt=0, le=100)] | None = None
    cartesian_speed_mm_s: Positive | None = None
    settle_after_program_s: NonNegative | None = None
    no_progress_s: NonNegative | None = None  # the watchdog's no-progress limit, 0: none (docs/robustness.md)


class Rail(Section):
    """A linear rail under the robot's base (docs/clients.md); defaults: the PreciseFlex
    PF400's 1 m rail as its controller configures it (GPL axis 6)."""
    direction: Vec3 = [1.0, 0.0, 0.0]     # travel direction in the robot base frame
    travel: Vec2 = [-500.0, 500.0]        # mm: the rail joint's range; 0 puts the base at robot.base
    speed: Positive = 750.0               # mm/s at 100 %
    acceleration: Positive = 1000.0       # mm/s2 at 100 %
    gpl_axis: Annotated[int, Field(ge=1, le=12)] = 6

    @field_validator("direction")
    @classmethod
    def _direction(cls, v: list[float]) -> list[float]:
        return _nonzero(v)

    @field_validator("travel")
    @classmethod
    def _travel(cls, v: list[float]) -> list[float]:
        if not v[0] <= 0.0 <= v[1] or v[0] == v[1]:
            raise ValueError("travel: [lowest, highest] mm, lowest below highest, 0 (the base pose) within")
        return v


class Robot(Section):
    model: str
    base: Pose6 = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    home: str = "start"
    rail: Rail | None = None


class Gripper(Section):
    type: Literal["fingers", "suction"] = "fingers"
    model: str
    site: str = "flange"
    prefix: str = "gripper/"
    gpl_signal: Output | None = None
    # suction only
    vacuum_kpa: Positive = 60.0          # vacuum level (below atmosphere) when on
    vacuum_output: Output | None = None  # output that turns the vacuum on (besides CLOSEI)
    blowoff_output: Output | None = None  # output that blows the part off
    vacuum_input: Input | None = None    # input on while the cup holds a part (vacuum sensed)
    # fingers only
    holding_input: Input | None = None   # input on while the jaws hold a part (a servo gripper's plate test)

    @model_validator(mode="after")
    def _suction_keys(self) -> "Gripper":
        if self.type == "fingers":
            used = [k for k in ("vacuum_output", "blowoff_output", "vacuum_input")
                    if getattr(self, k) is not None]
            if used:
                raise ValueError(f"{', '.join(used)}: only for type = \"suction\"")
        elif self.holding_input is not None:
            raise ValueError("holding_input: only for type = \"fingers\" (a cup has vacuum_input)")
        return self


class Table(Section):
    center: Vec3
    size: Size3


class Part(Section):
    name: str
    shape: Literal["box", "cylinder", "mesh"] = "box"
    size: Size3 | None = None          # box: full x, y, z mm
    radius: Positive | None = None     # cylinder
    height: Positive | None = None     # cylinder
    mesh: str | None = None            # mesh: a file trimesh reads (STL, OBJ, ...), in mm
    mass: Positive
    friction: Positive = 0.5
    rgba: Rgba = [0.9, 0.55, 0.1, 1.0]

    @model_validator(mode="after")
    def _shape_keys(self) -> "Part":
        need = {"box": ("size",), "cylinder": ("radius", "height"), "mesh": ("mesh",)}[self.shape]
        missing = [k for k in need if getattr(self, k) is None]
        if missing:
            raise ValueError(f"shape {self.shape!r} needs {', '.join(missing)}")
        extra = [k for k in ("size", "radius", "height", "mesh") if k not in need and getattr(self, k) is not None]
        if extra:
            raise ValueError(f"{', '.join(extra)}: not used by shape {self.shape!r}")
        return self


class Feeder(Section):
    name: str = "nest"
    part: str | None = None            # part type (default: the first [[part]])
    nest: Vec3
    nest_size: Size2 = [44.0, 44.0]
    nest_yaw: Finite = 0.0
    pool: Annotated[int, Field(ge=1, le=10000)]
    delay: NonNegative = 0.3
    jitter_xy: NonNegative = 0.0
    jitter_yaw: NonNegative = 0.0


class Encoder(Section):
    number: Annotated[int, Field(ge=1, le=16)]
    counts_per_mm: Positive = 10.0


class Conveyor(Section):
    name: str
    top_center: Vec3
    size: Size3                         # width, length, thickness mm
    direction: Annotated[list[Finite], Field(min_length=2, max_length=3)] = [1.0, 0.0]
    speed: NonNegative                  # mm/s
    accel: Positive = 1000.0            # mm/s^2 ramp
    running: bool = True                # at start (without run_output)
    run_output: Output | None = None
    reverse_output: Output | None = None
    rail_height: NonNegative = 8.0
    friction: Positive = 0.8
    place: bool = False                 # releasing a part on it is a put-down
    encoder: Encoder | None = None

    @field_validator("direction")
    @classmethod
    def _direction(cls, v: list[float]) -> list[float]:
        return _nonzero(v)


class Source(Section):
    name: str
    conveyor: str
    parts: Annotated[list[str], Field(min_length=1)] | None = None  # default: every [[part]]
    weights: Annotated[list[Positive], Field(min_length=1)] | None = None
    mean_interval: Positive = 2.0       # s between parts on average
    distribution: Literal["fixed", "uniform", "exponential"] = "exponential"
    min_gap: NonNegative = 60.0         # mm of belt between consecutive parts at least
    position: NonNegative = 30.0        # mm from the belt's upstream end to the part centre
    lateral: Finite = 0.0               # mm across the belt (+ = left of travel)
    jitter_lateral: NonNegative = 0.0   # mm, uniform +/-
    jitter_yaw: NonNegative = 0.0       # deg, uniform +/-
    yaw: Finite = 0.0                   # deg, relative to the belt
    pool: Annotated[int, Field(ge=1, le=10000)] = 40
    start: NonNegative = 0.0            # s: first part

    @model_validator(mode="after")
    def _weights(self) -> "Source":
        if self.weights is not None and (self.parts is None or len(self.weights) != len(self.parts)):
            raise ValueError("weights needs one value per entry of parts")
        return self


class Sensor(Section):
    name: str
    type: Literal["photo_eye", "presence"]
    input: Input
    # photo_eye
    conveyor: str | None = None
    position: Finite | None = None      # mm along the belt from its upstream end
    height: Positive = 5.0              # mm above the belt top
    latch_encoder: int | None = None
    # presence
    lo: Vec3 | None = None
    hi: Vec3 | None = None

    @model_validator(mode="after")
    def _type_keys(self) -> "Sensor":
        if self.type == "photo_eye":
            missing = [k for k in ("conveyor", "position") if getattr(self, k) is None]
            extra = [k for k in ("lo", "hi") if getattr(self, k) is not None]
        else:
            missing = [k for k in ("lo", "hi") if getattr(self, k) is None]
            extra = [k for k in ("conveyor", "position", "latch_encoder") if getattr(self, k) is not None]
        if missing:
            raise ValueError(f"a {self.type} needs {', '.join(missing)}")
        if extra:
            raise ValueError(f"{', '.join(extra)}: not used by a {self.type}")
        if self.lo is not None and not all(a < b for a, b in zip(self.lo, self.hi)):
            raise ValueError("lo must be below hi on every axis")
        return self


class Spreader(Section):
    center: Vec2 | None = None
    radius: Positive
    height: Positive


class Bin(Section):
    name: str = "bin"
    floor_center: Vec3
    inner_size: Size3
    wall: Positive = 8.0
    stand: bool = False
    spreader: Spreader | None = None
    place: bool = True                  # a part let go over it is put down (False: a reject bin)


class Tray(Section):
    name: str
    center: Vec3                        # centre of the tray floor's top face, world mm
    yaw: Finite = 0.0
    rows: Annotated[int, Field(ge=1, le=100)]   # along the tray's y
    cols: Annotated[int, Field(ge=1, le=100)]   # along the tray's x
    pitch: Size2                        # x, y mm between cell centres
    wall: Positive = 4.0
    wall_height: NonNegative = 6.0
    margin: NonNegative = 10.0          # mm of floor around the outer cells
    swap_when_full: bool = False        # an operator takes a full tray away (an empty one in its place)


class CameraCalibration(Section):
    file: str
    x: Annotated[list[Finite], Field(min_length=1)]
    y: Annotated[list[Finite], Field(min_length=1)]
    heights: Annotated[list[Annotated[float, Field(ge=1.0, allow_inf_nan=False)]], Field(min_length=2)] = [30.0, 110.0]
    plane_z: Finite = 0.0
    radius: Positive = 9.0
    rgba: Rgba = [0.0, 1.0, 0.0, 1.0]
    # A camera on the robot (mount): the hand-eye routine (twin/vision/handeye.py) moves it
    # over a dot plate lying at `plate` (world x, y, z of its top face, yaw); x, y, heights
    # and angles are then the flange's positions, heights and yaws, plane_z the plate's top.
    plate: Annotated[list[Finite], Field(min_length=4, max_length=4)] | None = None
    angles: Annotated[list[Finite], Field(min_length=1)] = [0.0]
    pitch: Positive = 10.0
    dot_radius: Positive = 3.0


class CameraLight(Section):
    pos: Vec3
    diffuse: Annotated[list[Annotated[float, Field(ge=0, le=1)]], Field(min_length=3, max_length=3)] = [0.5, 0.5, 0.5]


class CameraSection(Section):
    """[[camera]] (twin/physics/camera.py, docs/vision.md)."""
    name: str
    resolution: Annotated[list[Annotated[int, Field(gt=0, le=8192)]], Field(min_length=2, max_length=2)] = [640, 480]
    focal_px: Positive | None = None
    fov_deg: Annotated[float, Field(gt=0, lt=180)] | None = None
    pose: Pose6 = [0.0, 0.0, 1000.0, 0.0, 180.0, 0.0]
    mount: str | None = None
    distortion: Annotated[list[Finite], Field(min_length=5, max_length=5)] = [0.0, 0.0, 0.0, 0.0, 0.0]
    exposure: Positive = 1.0
    noise: NonNegative = 0.0
    seed: Seed = 0
    light: CameraLight | None = None
    depth_range_mm: Size2 = [50.0, 5000.0]
    calibration: CameraCalibration | None = None

    @model_validator(mode="after")
    def _focal(self) -> "CameraSection":
        if (self.focal_px is None) == (self.fov_deg is None):
            raise ValueError("give one of focal_px (pixels) or fov_deg (vertical field of view, deg)")
        return self


class Scatter(Section):
    """[[scatter]] (twin/physics/scatter.py)."""
    name: str
    parts: Annotated[list[str], Field(min_length=1)]
    count: Annotated[int, Field(ge=1, le=1000)]
    area: Annotated[list[Finite], Field(min_length=4, max_length=4)]
    mat: Annotated[list[Finite], Field(min_length=4, max_length=4)]
    mat_height: Positive = 2.0
    min_distance: NonNegative = 60.0
    upside_down: Annotated[float, Field(ge=0, le=1)] = 0.0

    @model_validator(mode="after")
    def _boxes(self) -> "Scatter":
        for key in ("area", "mat"):
            x0, y0, x1, y1 = getattr(self, key)
            if not (x0 < x1 and y0 < y1):
                raise ValueError(f"{key}: [x lo, y lo, x hi, y hi] with lo below hi")
        return self


class Vision(Section):
    """[vision]: twin/vision/process.py checks the processes and names the process and
    tool of a mistake."""
    time_s: NonNegative = 0.08
    process: list[dict[str, Any]] = []


class Region(Section):
    lo: Vec3
    hi: Vec3
    place: bool = False

    @model_validator(mode="after")
    def _ordered(self) -> "Region":
        if not all(a < b for a, b in zip(self.lo, self.hi)):
            raise ValueError("lo must be below hi on every axis")
        return self


class Scene(Section):
    physics: Physics = Physics()
    controller: Controller = Controller()
    robot: Robot
    gripper: Gripper
    table: Table | None = None
    part: Annotated[list[Part], Field(min_length=1)]
    feeder: list[Feeder] = []
    conveyor: list[Conveyor] = []
    source: list[Source] = []
    sensor: list[Sensor] = []
    bin: list[Bin] = []
    tray: list[Tray] = []
    scatter: list[Scatter] = []
    camera: list[CameraSection] = []
    vision: Vision | None = None
    regions: dict[str, Region] = {}
    locations: dict[str, Pose6] = {}

    @model_validator(mode="after")
    def _references(self) -> "Scene":
        if self.robot.home not in self.locations:
            raise ValueError(f"robot.home: location {self.robot.home!r} is not in [locations]"
                             f" (has: {', '.join(self.locations) or 'none'})")
        kinds = {"part": self.part, "feeder": self.feeder, "conveyor": self.conveyor,
                 "source": self.source, "sensor": self.sensor, "bin": self.bin, "tray": self.tray,
                 "camera": self.camera, "scatter": self.scatter}
        for kind, items in kinds.items():
            names = [c.name for c in items]
            for i, name in enumerate(names):
                if name in names[:i]:
                    raise ValueError(f"{kind}[{i}].name: {name!r} is used twice")
        parts = [p.name for p in self.part]
        conveyors = {c.name: c for c in self.conveyor}
        encoders = [c.encoder.number for c in self.conveyor if c.encoder is not None]
        if len(set(encoders)) != len(encoders):
            raise ValueError("conveyor[*].encoder.number: each encoder needs its own number")
        for i, f in enumerate(self.feeder):
            _known(f"feeder[{i}].part", f.part, parts, "[[part]]")
        for i, sc in enumerate(self.scatter):
            for j, p in enumerate(sc.parts):
                _known(f"scatter[{i}].parts[{j}]", p, parts, "[[part]]")
        for i, s in enumerate(self.source):
            _known(f"source[{i}].conveyor", s.conveyor, list(conveyors), "[[conveyor]]")
            for j, p in enumerate(s.parts or []):
                _known(f"source[{i}].parts[{j}]", p, parts, "[[part]]")
            if s.position > conveyors[s.conveyor].size[1]:
                raise ValueError(f"source[{i}].position: {s.position:g} mm is beyond the belt's "
                                 f"length ({conveyors[s.conveyor].size[1]:g} mm)")
        for i, s in enumerate(self.sensor):
            if s.type == "photo_eye":
                _known(f"sensor[{i}].conveyor", s.conveyor, list(conveyors), "[[conveyor]]")
                length = conveyors[s.conveyor].size[1]
                if not 0.0 <= s.position <= length:
                    raise ValueError(f"sensor[{i}].position: {s.position:g} mm is off the belt "
                                     f"(0 to {length:g} mm)")
                if s.latch_encoder is not None and s.latch_encoder not in encoders:
                    raise ValueError(f"sensor[{i}].latch_encoder: no conveyor has encoder "
                                     f"{s.latch_encoder} (encoders: {encoders or 'none'})")
        inputs = [s.input for s in self.sensor] + [
            i for i in (self.gripper.vacuum_input, self.gripper.holding_input) if i is not None]
        for i, s in enumerate(self.sensor):
            if inputs.count(s.input) > 1:
                raise ValueError(f"sensor[{i}].input: input {s.input} is wired twice")
        return self


def _known(where: str, name: str | None, names: list[str], table: str) -> None:
    if name is not None and name not in names:
        raise ValueError(f"{where}: {name!r} is not a {table} (has: {', '.join(names) or 'none'})")


# ------------------------------------------------------------------ error messages
def validate_scene(raw: dict, path: str | Path) -> Scene:
    """The scene as typed models, or SceneError with one located, readable message."""
    try:
        return Scene.model_validate(raw)
    except ValidationError as err:
        errors = err.errors(include_url=False)
        # A misspelt key is also a missing one: name the misspelling, it says more.
        first = min(errors, key=lambda e: e["type"] != "extra_forbidden")
        raise SceneError(_message(first), file=str(path)) from None


def _message(error: dict) -> str:
    loc = tuple(error["loc"])
    kind = error["type"]
    if kind == "extra_forbidden":
        parent, key = _model_at(loc[:-1]), str(loc[-1])
        allowed = sorted(parent.model_fields) if parent is not None else []
        close = difflib.get_close_matches(key, allowed, n=1)
        hint = f"; did you mean {close[0]}?" if close else ""
        if len(loc) > 1:
            what = f"key {key!r} in {_path(loc[:-1])}"
        elif isinstance(error.get("input"), (dict, list)):
            what = f"section [{key}]"
        else:
            what = f"key {key!r} at the top level (before the first section)"
        return f"unknown {what} (known: {', '.join(allowed)}{hint})"
    where = _path(loc)
    msg = error["msg"]
    got = error.get("input")
    shown = f", got {got!r}" if not isinstance(got, dict) else ""
    if kind == "value_error":
        msg = msg.removeprefix("Value error, ") + shown
        return f"{where}: {msg}" if where else msg
    if kind == "missing":
        return f"{where}: missing (required)"
    expected = {"float_type": "a number", "int_type": "an integer", "string_type": "a string",
                "bool_type": "true or false", "list_type": "a list", "model_type": "a table",
                "dict_type": "a table", "finite_number": "a finite number (not nan or inf)",
                "literal_error": msg.removeprefix("Input should be ").replace("'", '"')}.get(kind)
    if expected is not None:
        return f"{where}: expected {expected}{shown}"
    return f"{where}: {msg[0].lower() + msg[1:]}{shown}"


def _path(loc: tuple) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _model_at(loc: tuple) -> type[BaseModel] | None:
    """The section model at a key path (list indices and table keys stepped through), for
    the list of known keys."""
    model: Any = Scene
    for part in loc:
        model = _unwrap(model)
        if get_origin(model) is dict:  # `part` is a key of a free table: its value's type
            model = get_args(model)[1]
        elif get_origin(model) is list:  # `part` is an index
            model = get_args(model)[0]
        elif isinstance(model, type) and issubclass(model, BaseModel) and part in model.model_fields:
            model = model.model_fields[part].annotation
        else:
            return None
    model = _unwrap(model)
    return model if isinstance(model, type) and issubclass(model, BaseModel) else None


def _unwrap(annotation: Any) -> Any:
    """X | None and Annotated[X, ...] -> X (lists and dicts are kept)."""
    while True:
        origin = get_origin(annotation)
        if origin is Annotated:
            annotation = get_args(annotation)[0]
        elif origin in (Union, types.UnionType):
            annotation = [a for a in get_args(annotation) if a is not type(None)][0]
        else:
            return annotation
