"""Conveyor tracking (eV+ Language User's Guide, "Conveyor Tracking"; V+ guide v17, same
chapter; docs/vplus.md "Conveyor tracking" for what the reference guide decides).

Belt variables (`%name`) hold a `controller.belt.BeltFrame`; ``%belt:loc`` is a
`BeltLocation`, which the motion instructions hand to the controller: the robot then
follows the part every servo step.  DEVICE/SETDEVICE read the same encoders as the
external-encoder device (type 0, units 0 and 1 are encoders 1 and 2).
"""

from __future__ import annotations

from dataclasses import dataclass
from weakref import WeakKeyDictionary

from ....controller.belt import MAX_VEL_AVG, VELOCITY_CYCLE_S, BeltFrame, BeltLocation, BeltWindow, count_difference, counter
from ....controller.controller import BELT_NOT_ENABLED
from .. import messages as msg
from ..values import fail, to_int
from . import INSTRUCTIONS, Any, function, instruction, motion  # noqa: F401 (APPROS, aliased below)
from .locations import location_arg

MAX_ENCODERS = 6  # "Six belt encoders are supported" (eV+ guide, "The Belt Encoder")
DEVICE_UNITS = 2  # external encoder units 0 and 1 (eV+ guide, "External Encoder Device")
PREDICTION_S = 0.032  # DEVICE select 3: "predicted 32 milliseconds in the future"
WINDOW_PRIORITY = 1  # a WINDOW error program's default priority (a REACT's default)


def _enabled(rt) -> None:
    if not rt.switch("BELT"):
        raise fail(BELT_NOT_ENABLED, "ENABLE BELT first")


def _encoder(rt, number):
    encoders = getattr(rt.robot.cell, "encoders", None) or {}
    n = to_int(number)
    if not 1 <= n <= MAX_ENCODERS:
        raise fail(msg.ILLEGAL_VALUE, f"belt encoder {n} (1 to {MAX_ENCODERS})")
    if n not in encoders:
        raise fail(msg.DEVICE_NOT_READY, f"the cell has no belt encoder {n}")
    return encoders[n]


def belt_arg(value) -> BeltFrame:
    if isinstance(value, tuple) and len(value) == 2 and isinstance(value[0], dict):  # %belt[i]: (array, index)
        array, index = value
        value = array.get(index)
    if value is None:
        raise fail(msg.UNDEFINED_VALUE, "belt variable not defined by DEFBELT")
    if not isinstance(value, BeltFrame):
        raise fail(msg.WRONG_TYPE, "belt variable expected")
    return value


def _store(target, belt: BeltFrame):
    """DEFBELT's result: into %belt[i] directly, or written back to a plain %belt."""
    if isinstance(target, tuple) and len(target) == 2 and isinstance(target[0], dict):
        array, index = target
        array[index] = belt
        return None
    return (belt,)


@instruction("DEFBELT", targets=True, writes_back=True)
def _defbelt(rt, *items: Any):
    """DEFBELT %belt = nominal, encoder, vel_avg, scale: a belt variable on encoder 1..6;
    its speed averaged over vel_avg 16-ms cycles (1..64), scale in mm/count."""
    _enabled(rt)
    *values, target = items
    if len(values) != 4 or any(v is None for v in (values[0], values[1], values[3])):
        raise fail(msg.INVALID_ARGUMENT, "DEFBELT %belt = nominal, encoder, vel_avg, scale")
    nominal, number, vel_avg, scale = values
    scale = float(scale)
    if scale == 0.0:
        raise fail(msg.ILLEGAL_VALUE, "belt scale 0")
    belt = BeltFrame(location_arg(nominal), _encoder(rt, number), scale,
                     vel_avg=min(max(to_int(vel_avg or 1), 1), MAX_VEL_AVG))
    belt.speed_source = rt.robot.belts.speed_of
    parameters = rt.system.parameters
    belt.mode_source = lambda: int(parameters["BELT.MODE"])
    return _store(target, belt)


@instruction("SETBELT", targets=True)
def _setbelt(rt, offset, target: Any):
    """SETBELT %belt = offset: the encoder count at which the belt frame is nominal."""
    _enabled(rt)
    belt_arg(target).offset = counter(to_int(offset))


@instruction("WINDOW", targets=True, name_values=(2,))
def _window(rt, *items: Any):
    """WINDOW %belt = upstream, downstream[, program[, priority]]: the working range; a
    violation calls `program` like a reaction (none: an error stops the program)."""
    _enabled(rt)
    *values, target = items
    belt = belt_arg(target)
    if len(values) < 2 or values[0] is None or values[1] is None or len(values) > 4:
        raise fail(msg.INVALID_ARGUMENT, "WINDOW %belt = upstream, downstream, program, priority")
    belt.window = BeltWindow.between(belt.nominal, location_arg(values[0]), location_arg(values[1]))
    rt.robot.belts.show_window(belt)
    program = values[2] if len(values) > 2 else None
    priority = WINDOW_PRIORITY if len(values) < 4 or values[3] is None else to_int(values[3])
    belt.on_violation = None if program is None else rt.window_reaction(program, priority)


@function("BELT")
def _belt(rt, belt: Any, mode=0):
    """BELT(%belt, mode): mode 0 the encoder counter now; 2 the oldest photo-eye latch not
    read yet (counts); otherwise the speed in counts per 16-ms cycle, averaged as DEFBELT
    asked (docs/vplus.md)."""
    belt = belt_arg(belt)
    mode = to_int(mode or 0)
    if mode == 0:
        return float(counter(belt.encoder.counts()))
    if mode == 2:
        return _latched_count(belt)
    return rt.robot.belts.counts_per_second(belt.encoder_number, belt.vel_avg) * VELOCITY_CYCLE_S


@function("BSTATUS")
def _bstatus(rt):
    """BSTATUS: 1 tracking a belt, 2 waiting for a destination upstream of its window,
    4 a destination downstream, 8 a window violation since the last BSTATUS."""
    return float(rt.robot.bstatus())


@function("WINDOW")
def _window_test(rt, where: Any, time_ms=0.0, mode=0):
    """WINDOW(%belt:loc, time, mode): mm from the downstream limit (mode 0; negative once
    past it) or past the upstream limit (mode 1; negative before it), `time` ms from now;
    both are positive inside the window."""
    if not isinstance(where, BeltLocation):
        raise fail(msg.WRONG_TYPE, "WINDOW needs a belt-relative location")
    if where.belt.window is None:
        raise fail(msg.UNDEFINED_VALUE, "no WINDOW for this belt")
    to_downstream, past_upstream = where.belt.window_distances(where.relative, float(time_ms or 0.0) / 1000.0)
    return past_upstream if to_int(mode or 0) > 0 else to_downstream


@function("LATCHED")
def _latched(rt, select=0):
    """LATCHED(-n): the photo-eye latches of belt encoder n not yet read by BELT(%b, 2) or
    DEVICE; LATCHED(robot): the robot has no latch input wired, 0 (docs/vplus.md)."""
    n = to_int(select or 0)
    if n >= 0:
        return 0.0
    return float(len(_encoder(rt, -n).latches))


# The chapter's text and sample program write APPROX for the straight-line approach
# ("APPROX, DEPARTS, MOVES, and MOVEST can be used"): the same instruction as APPROS.
INSTRUCTIONS["APPROX"] = INSTRUCTIONS["APPROS"]


# ---------------------------------------------------------------- external encoder device
@dataclass
class _Unit:
    scale: float = 1.0  # mm per count
    offset: float = 0.0  # mm
    lower: float | None = None
    upper: float | None = None


_UNITS: WeakKeyDictionary = WeakKeyDictionary()  # system -> SETDEVICE settings per unit


def _device_unit(rt, kind, unit) -> tuple[_Unit, object]:
    if to_int(kind) != 0:
        raise fail(msg.ILLEGAL_VALUE, f"device type {to_int(kind)} (the external encoders are type 0)")
    u = to_int(unit)
    if not 0 <= u < DEVICE_UNITS:
        raise fail(msg.ILLEGAL_VALUE, f"external encoder unit {u} (0 or 1)")
    units = _UNITS.setdefault(rt.system, {})
    return units.setdefault(u, _Unit()), _encoder(rt, u + 1)


@instruction("SETDEVICE")
def _setdevice(rt, unit: tuple, items: tuple):
    """SETDEVICE (0, unit, error, command) p1, p2: 0 initialise, 1 reset, 8 scale (mm/count),
    9 offset (mm), 10 limits (mm; an omitted one is not checked)."""
    kind, number, _error, command = (tuple(unit) + (None,) * 4)[:4]
    state, _ = _device_unit(rt, kind, number)
    p1, p2 = (tuple(items) + (None, None))[:2]
    command = to_int(command or 0)
    if command == 0:
        state.__init__()
    elif command == 8:
        if p1 is None or float(p1) == 0.0:
            raise fail(msg.ILLEGAL_VALUE, "SETDEVICE scale")
        state.scale = float(p1)
    elif command == 9:
        state.offset = float(p1 or 0.0)
    elif command == 10:
        state.lower = None if p1 is None else float(p1)
        state.upper = None if p2 is None else float(p2)
    elif command != 1:
        raise fail(msg.ILLEGAL_VALUE, f"SETDEVICE command {command}")


@function("DEVICE")
def _device(rt, kind, unit, error: Any = None, select=0):
    """DEVICE(0, unit, error, select): 0 status (no error bits), 1 position, 2 velocity,
    3 position predicted 32 ms ahead, 4 position at the last latch (mm, mm/s)."""
    state, encoder = _device_unit(rt, kind, unit)
    select = to_int(select or 0)
    if select == 0:
        return 0.0
    speed = rt.robot.belts.counts_per_second(encoder.number) * state.scale
    if select == 2:
        return speed
    if select == 4:
        if not encoder.latches:
            raise fail(msg.UNDEFINED_VALUE, f"encoder {encoder.number} has not latched")
        count = encoder.latches[-1][1]
    elif select in (1, 3):
        count = encoder.counts()
    else:
        raise fail(msg.ILLEGAL_VALUE, f"DEVICE select {select}")
    position = state.scale * count_difference(count, 0) - state.offset
    if select == 3:
        position += speed * PREDICTION_S
    if state.lower is not None:
        position = max(position, state.lower)
    if state.upper is not None:
        position = min(position, state.upper)
    return position


def _latched_count(belt: BeltFrame) -> float:
    """BELT(%belt, 2): the oldest unread photo-eye latch of the belt's encoder (counts)."""
    latches = belt.encoder.latches
    if not latches:
        raise fail(msg.UNDEFINED_VALUE, f"encoder {belt.encoder_number} has no latch waiting")
    return float(counter(latches.popleft()[1]))
