"""Motion and hand instructions; they drive the shared virtual controller (rt.robot).

Locations are transformations (`Location`) or precision points (tuples of joint values,
degrees and mm).  The CP switch (ENABLE/DISABLE CP) is read when a motion is issued.
Modifiers that take ALWAYS here are written with it as a keyword name (`CPOFF ALWAYS`,
`SINGLE ALWAYS`, `OVERLAP ALWAYS`); a value setting takes it as a keyword argument
(`DURATION t ALWAYS`).
"""

from __future__ import annotations

from ....controller.belt import BeltLocation
from ....controller.location import Location, approach
from .. import messages as msg
from ..values import fail, to_int
from . import Loc, Point, function, instruction
from .locations import location_arg


def _cp(rt) -> bool:
    return rt.switch("CP")


def _destination(value):
    """A motion's target: a Location, or a precision point's joint values."""
    if isinstance(value, (tuple, BeltLocation)):
        return value
    return location_arg(value)


def _as_location(rt, value) -> Location:
    """A transformation for APPRO and straight-line motions (a precision point converted)."""
    if isinstance(value, tuple):
        return rt.robot.location_of_joints(value)
    if isinstance(value, BeltLocation):  # the controller follows the belt
        return value
    return location_arg(value)


def _dry_run(rt) -> bool:
    """DRY.RUN: "robot motion instructions are ignored", the robot stays attached to the
    task ([000] L750-751, L778-779, L5853)."""
    if not rt.switch("DRY.RUN"):
        return False
    rt.robot_for_motion()
    return True


def _always(names: tuple) -> bool:
    extra = [n for n in names if n != "ALWAYS"]
    if extra:
        raise fail(msg.INVALID_ARGUMENT, " ".join(extra))
    return bool(names)


@instruction("MOVE", waits=True)
def _move(rt, loc: Point):
    if _dry_run(rt):
        return
    yield from rt.robot.move(_destination(loc), straight=False, cp=_cp(rt))


@instruction("MOVES", waits=True)
def _moves(rt, loc: Point):
    if _dry_run(rt):
        return
    yield from rt.robot.move(_as_location(rt, loc), straight=True, cp=_cp(rt))


@instruction("APPRO", waits=True)
def _appro(rt, loc: Point, distance=None):
    if _dry_run(rt):
        return
    yield from rt.robot.move(approach(_as_location(rt, loc), distance or 0.0), straight=False, cp=_cp(rt))


@instruction("APPROS", waits=True)
def _appros(rt, loc: Point, distance=None):
    if _dry_run(rt):
        return
    yield from rt.robot.move(approach(_as_location(rt, loc), distance or 0.0), straight=True, cp=_cp(rt))


@instruction("DEPART", waits=True)
def _depart(rt, distance):
    if _dry_run(rt):
        return
    yield from rt.robot.move(approach(rt.robot.destination(), distance), straight=False, cp=_cp(rt))


@instruction("DEPARTS", waits=True)
def _departs(rt, distance):
    if _dry_run(rt):
        return
    yield from rt.robot.move(approach(rt.robot.destination(), distance), straight=True, cp=_cp(rt))


@instruction("MOVET", waits=True)
def _movet(rt, loc: Point, hand):
    """MOVET loc, hand: MOVE with the hand operated as the motion starts; a pneumatic hand
    opens for an opening above 0 and closes otherwise (docs/motion.md)."""
    if _dry_run(rt):
        return
    rt.robot.hand_at_next_motion(_hand_for_opening(hand))
    yield from _move(rt, loc)


@instruction("MOVEST", waits=True)
def _movest(rt, loc: Point, hand):
    if _dry_run(rt):
        return
    rt.robot.hand_at_next_motion(_hand_for_opening(hand))
    yield from _moves(rt, loc)


def _hand_for_opening(opening) -> str:
    return "open" if float(opening) > 0.0 else "close"


@instruction("READY", waits=True)
def _ready(rt):
    """READY: a joint motion to the robot's READY location, in its standard configuration."""
    if _dry_run(rt):
        return
    yield from rt.robot.move(rt.robot.ready_joints(), straight=False, cp=_cp(rt))


@function("INRANGE")
def _inrange(rt, loc: Point):
    """INRANGE(loc): 0 if the robot can reach loc, otherwise bits saying why not."""
    return float(rt.robot.inrange(_destination(loc)))


@function("CONFIG")
def _config(rt, select=0):
    return float(rt.robot.configuration(int(select or 0)))


@instruction("DRIVE", waits=True)
def _drive(rt, joint, change, speed=None):
    if _dry_run(rt):
        return
    yield from rt.robot.drive(int(joint), float(change), 100.0 if speed is None else float(speed), cp=_cp(rt))


@instruction("ALIGN", waits=True)
def _align(rt):
    if _dry_run(rt):
        return
    yield from rt.robot.move(rt.robot.aligned(), straight=True, cp=_cp(rt))


@instruction("BREAK", waits=True)
def _break(rt):
    yield from rt.robot.wait_stopped()


@instruction("DELAY", waits=True)
def _delay(rt, seconds):
    if _dry_run(rt):  # no motion to stop: the program still waits its time
        yield from rt.sleep(max(seconds, 0.0))
        return
    yield from rt.robot.dwell(seconds)


# ---------------------------------------------------------------- motion modifiers
ACCEL_PROFILES = range(0, 9)  # profile numbers the LRG allows; only profile 0 is defined here


@instruction("ACCEL")
def _accel(rt, accel=None, decel=None, *, profile=None):
    """ACCEL (profile) accel, decel: the V+ Language Reference's optional acceleration
    profile (0 to 8) comes first.  The twin's robots define only profile 0 (the square-wave
    acceleration), and "if a profile is specified that has not been defined, profile 0 is
    used": the number is kept for ACCEL(0), the motion is profile 0's (docs/motion.md)."""
    if profile is not None:
        number = to_int(profile)
        if number not in ACCEL_PROFILES:
            raise fail(msg.ILLEGAL_VALUE, f"ACCEL profile {number} (0 to 8)")
        rt.robot_for_motion()
        rt.system.accel_profile = number
    rt.robot.set_accel(accel, decel)


@function("ACCEL")
def _accel_value(rt, select=1):
    """ACCEL(0): the acceleration profile, ACCEL(1): acceleration %, ACCEL(2): deceleration %."""
    which = to_int(select)
    if which == 0:
        return float(rt.system.accel_profile)
    settings = rt.robot.settings
    return settings.decel if which == 2 else settings.accel


@instruction("DURATION")
def _duration(rt, seconds, *, always=False):
    """DURATION t [ALWAYS]: the next motion, or every motion, takes at least t seconds."""
    rt.robot.set_duration(float(seconds), always)


@instruction("CPON", names=True)
def _cpon(rt, *names):
    rt.robot.set_modifier("cp", True, _always(names))


@instruction("CPOFF", waits=True, names=True)
def _cpoff(rt, *names):
    """CPOFF breaks continuous path: it waits for the robot to stop (V+ guide v17 L6454)."""
    always = _always(names)
    yield from rt.robot.wait_stopped()
    rt.robot.set_modifier("cp", False, always)


def _modifier(name: str, key: str, value: bool) -> None:
    """A motion modifier that takes ALWAYS (V+ guide v17, "Motion Modifiers")."""
    instruction(name, names=True)(lambda rt, *names: rt.robot.set_modifier(key, value, _always(names)))


for _name, _key, _value in (("SINGLE", "single", True), ("MULTIPLE", "single", False),
                            ("COARSE", "coarse", True), ("FINE", "coarse", False),
                            ("NULL", "null", True), ("NONULL", "null", False),
                            ("OVERLAP", "overlap", True), ("NOOVERLAP", "overlap", False)):
    _modifier(_name, _key, _value)


@instruction("BRAKE")
def _brake(rt):
    """BRAKE: the robot decelerates to a stop at once, on its path; the motion is over
    (V+ guide v17 L6458-6461: "from any program task")."""
    rt.robot.stop()


@instruction("PAYLOAD")
def _payload(rt, percent):
    """PAYLOAD percent: the payload indication, 0 to 100 % of the maximum payload.  Recorded
    only: the twin's servos use the model's real masses (docs/motion.md)."""
    if not 0.0 <= float(percent) <= 100.0:
        raise fail(msg.ILLEGAL_VALUE, f"PAYLOAD {percent}")
    rt.robot.set_modifier("payload", float(percent), always=True)


@instruction("RIGHTY")
def _righty(rt):
    rt.robot.request_configuration(righty=True)


@instruction("LEFTY")
def _lefty(rt):
    rt.robot.request_configuration(righty=False)


# A 4-axis SCARA and a Cartesian robot have no elbow-up/down or wrist-flip choice: the
# controller accepts the requests and has nothing to change (docs/motion.md).
for _name in ("ABOVE", "BELOW", "FLIP", "NOFLIP"):
    instruction(_name)(lambda rt: None)


# ---------------------------------------------------------------- TOOL and BASE
@instruction("TOOL", waits=True)
def _tool(rt, loc: Loc):
    yield from rt.robot.set_tool(location_arg(loc))


@function("TOOL")
def _tool_value(rt):
    return rt.robot.tool


@instruction("BASE", waits=True)
def _base(rt, dx=None, dy=None, dz=None, rotation=None):
    """BASE dx, dy, dz, rotation: the world frame shifted by (dx, dy, dz) mm and turned by
    `rotation` degrees about Z, relative to the robot (V+ guide v17, "BASE")."""
    shift = Location(dx or 0.0, dy or 0.0, dz or 0.0, rotation or 0.0, 0.0, 0.0)
    yield from rt.robot.set_base(shift)


@function("BASE")
def _base_value(rt):
    return rt.robot.base


# ---------------------------------------------------------------- hand
# OPEN/CLOSE/RELAX act at the start of the next motion; the I forms wait
# for the robot to stop, act at once and then wait HAND.TIME (V+ guide v17,
# "Hand Control").
@instruction("OPEN")
def _open(rt):
    rt.robot.hand_at_next_motion("open")


@instruction("CLOSE")
def _close(rt):
    rt.robot.hand_at_next_motion("close")


@instruction("RELAX")
def _relax(rt):
    rt.robot.hand_at_next_motion("relax")


def _hand_now(rt, state: str):
    yield from rt.robot.wait_stopped()
    rt.robot.hand(state)
    yield from rt.sleep(rt.hand_time())


@instruction("OPENI", waits=True)
def _openi(rt):
    yield from _hand_now(rt, "open")


@instruction("CLOSEI", waits=True)
def _closei(rt):
    yield from _hand_now(rt, "close")


@instruction("RELAXI", waits=True)
def _relaxi(rt):
    yield from _hand_now(rt, "relax")
