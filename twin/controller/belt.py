"""Belt frames: reference frames fixed to a moving conveyor, read through its encoder.

One model serves both languages: a V+ belt variable (DEFBELT, SETBELT, WINDOW; eV+
Language User's Guide, "Conveyor Tracking") and a GPL conveyor RefFrame (Type 2,
ConveyorRobot, ConveyorOffset; GPL User Manual, "Conveyor Reference Frame").

The guides' arithmetic, exactly:

    instantaneous_XYZ = nominal_XYZ + belt_distance * X_direction_of_nominal
    belt_distance     = (encoder_count - encoder_offset) * scale      (mm/count)

the difference taken on the 24-bit signed counter, so that a rollover between the
offset and the reading does not matter.  The orientation of a belt frame is always the
nominal one (the belt runs straight in the robot's working area).

The window is a stretch of the belt between two planes perpendicular to the travel,
kept here as two positions along the nominal X axis (mm from the nominal origin).

An encoder is what the cell provides (docs/scene.md): `number`, `counts_per_mm`,
`counts()` (the 24-bit counter now), `latches` (a deque of (sim time s, count), one
per photo-eye latch) and `latch_input`.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Callable, Protocol

import numpy as np

from .location import Location

COUNTER_BITS = 24  # "the count is stored as a signed 24-bit number" (eV+ guide, "The Belt Encoder")
_COUNTER_RANGE = 1 << COUNTER_BITS
_COUNTER_HALF = 1 << (COUNTER_BITS - 1)
VELOCITY_CYCLE_S = 0.016  # the belt speed is kept per 16-ms cycle (V+ guide v17, encoder NOTE)
MAX_VEL_AVG = 64  # DEFBELT averages the speed over at most 64 cycles (docs/vplus.md)


class Encoder(Protocol):
    number: int
    counts_per_mm: float
    latch_input: int | None
    latches: "collections.deque[tuple[float, int]]"  # noqa: F821 (documented type)

    def counts(self) -> int: ...


def counter(value: int) -> int:
    """A count as the 24-bit signed counter holds it (it rolls over at +/-2^23)."""
    return ((int(value) + _COUNTER_HALF) % _COUNTER_RANGE) - _COUNTER_HALF


def count_difference(reading: int, offset: int) -> int:
    """reading - offset on the 24-bit counter: right across a rollover."""
    return counter(int(reading) - int(offset))


@dataclass
class BeltWindow:
    """The working range along the belt: positions (mm) along the nominal X axis."""

    upstream: float
    downstream: float

    @classmethod
    def between(cls, nominal: Location, a: Location, b: Location) -> "BeltWindow":
        """WINDOW %b = a, b: planes through a and b, perpendicular to the travel; the one
        further up the belt is the upstream limit, whichever is given first."""
        xa, xb = ((nominal.inverse() * loc).x for loc in (a, b))
        return cls(min(xa, xb), max(xa, xb))


@dataclass
class BeltFrame:
    """A frame fixed to a moving belt (a V+ belt variable, a GPL conveyor RefFrame).

    `scale` is mm per count (negative if the counter decreases as the belt moves along
    +X); `offset` the encoder offset (counts).  `vel_avg`: the number of 16-ms cycles
    the speed is averaged over (DEFBELT's third argument)."""

    nominal: Location
    encoder: Encoder
    scale: float
    vel_avg: int = 1
    offset: int = 0
    window: BeltWindow | None = None
    name: str = ""
    # Called on a window violation instead of raising it (V+ WINDOW's error program).
    on_violation: Callable[[str], None] | None = field(default=None, repr=False)
    speed_source: Callable[["BeltFrame"], float] | None = field(default=None, repr=False)
    mode_source: Callable[[], int] | None = field(default=None, repr=False)  # V+ BELT.MODE

    @property
    def mode(self) -> int:
        return 0 if self.mode_source is None else int(self.mode_source())

    @property
    def encoder_number(self) -> int:
        return self.encoder.number

    def travel(self, reading: int | None = None) -> float:
        """belt_distance (mm) for an encoder reading (now if None)."""
        reading = self.encoder.counts() if reading is None else reading
        return count_difference(reading, self.offset) * self.scale

    def direction(self) -> np.ndarray:
        """The unit travel direction (the nominal X axis) in the program's world frame."""
        return self.nominal.rotation()[:, 0]

    def at_travel(self, travel: float) -> Location:
        """The frame when the belt has moved `travel` mm from the offset."""
        return self.nominal * Location(float(travel), 0.0, 0.0, 0.0, 0.0, 0.0)

    def instantaneous(self) -> Location:
        return self.at_travel(self.travel())

    def speed(self) -> float:
        """Belt speed along +X, mm/s, averaged as DEFBELT asked (see BeltMonitor)."""
        if self.speed_source is None:
            return 0.0
        return self.speed_source(self)

    def position_along(self, relative: Location, seconds_ahead: float = 0.0) -> float:
        """Where `relative` (a location in this frame) is along the belt, mm from the
        nominal origin, now or `seconds_ahead` from now at the present speed."""
        return self.travel() + relative.x + self.speed() * seconds_ahead

    def window_distances(self, relative: Location, seconds_ahead: float = 0.0) -> tuple[float, float]:
        """(distance to the downstream limit, distance past the upstream limit), mm:
        both positive inside the window (see WINDOW() in docs/vplus.md)."""
        if self.window is None:
            return float("inf"), float("inf")
        x = self.position_along(relative, seconds_ahead)
        return self.window.downstream - x, x - self.window.upstream

    def window_state(self, relative: Location, seconds_ahead: float = 0.0) -> str:
        """'inside', 'upstream' (not there yet) or 'downstream' (gone past)."""
        to_downstream, past_upstream = self.window_distances(relative, seconds_ahead)
        if to_downstream < 0.0:
            return "downstream"
        if past_upstream < 0.0:
            return "upstream"
        return "inside"


@dataclass(frozen=True)
class BeltLocation:
    """``%belt:loc``: a location fixed to a belt, `relative` in the belt frame."""

    belt: BeltFrame
    relative: Location

    def __mul__(self, other: Location) -> "BeltLocation":
        if not isinstance(other, Location):
            return NotImplemented
        return BeltLocation(self.belt, self.relative * other)

    def instantaneous(self) -> Location:
        return self.belt.instantaneous() * self.relative

    def window_state(self, seconds_ahead: float = 0.0) -> str:
        return self.belt.window_state(self.relative, seconds_ahead)


class BeltMonitor:
    """Samples every encoder once per servo step (the controller's belt interface): the
    averaged speed a belt frame reports, and the prediction the window tests use."""

    def __init__(self, cell, dt: float):
        self.cell = cell  # its `encoders` (none on a cell without conveyors)
        self.dt = dt
        self.cycle_steps = max(1, int(round(VELOCITY_CYCLE_S / dt)))
        self._depth = MAX_VEL_AVG * self.cycle_steps + 1
        self._history: dict[int, deque] = {}
        self.frames: list[BeltFrame] = []  # the programs' belt frames with a window, for the recording

    def show_window(self, belt: BeltFrame) -> None:
        """A program set `belt`'s window (V+ WINDOW, a GPL conveyor RefFrame's limits): the
        recording draws it from the next frame on."""
        if belt not in self.frames:
            self.frames.append(belt)

    @property
    def encoders(self) -> dict[int, Encoder]:
        return getattr(self.cell, "encoders", None) or {}

    def sample(self) -> None:
        for number, encoder in self.encoders.items():
            history = self._history.get(number)
            if history is None:
                history = self._history[number] = deque(maxlen=self._depth)
            history.append(int(encoder.counts()))

    def counts_per_second(self, number: int, cycles: int = 1) -> float:
        """The encoder's rate (counts/s), averaged over `cycles` 16-ms cycles."""
        history = self._history.get(number, ())
        steps = min(max(1, int(cycles)) * self.cycle_steps, len(history) - 1)
        if steps < 1:
            return 0.0
        return count_difference(history[-1], history[-1 - steps]) / (steps * self.dt)

    def speed_of(self, belt: BeltFrame) -> float:
        return self.counts_per_second(belt.encoder_number, belt.vel_avg) * belt.scale


def conveyor_nominal(cell, number: int) -> Location | None:
    """The frame of the conveyor whose encoder is `number`, in the robot base frame (mm):
    the centre of the belt's top face, X along the travel (docs/scene.md).  None when no
    conveyor of the cell carries that encoder."""
    for conveyor in (getattr(cell, "conveyors", None) or {}).values():
        encoder = getattr(conveyor, "encoder", None)
        if encoder is not None and encoder.number == number:
            T = np.linalg.inv(cell.robot_base_pose()) @ conveyor.frame_world
            T[:3, 3] *= 1000.0
            return Location.from_matrix(T)
    return None
