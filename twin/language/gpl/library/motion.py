"""GPL Profile objects and the global Move class (User Manual ch. 12,
L1916-1990), on the shared VirtualController.

How a motion maps onto the controller (docs/gpl.md, "Built-in classes"):
* ``Profile.Speed`` (percent of nominal) is the controller's speed for that one
  motion; ``Controller.SystemSpeed`` (the monitor speed) scales every motion, as
  on the real controller.  For a straight line, 100 % is the controller's
  nominal Cartesian speed (scene ``cartesian_speed_mm_s``).
* ``Profile.Accel`` / ``Decel`` (percent of nominal) are the controller's
  acceleration and deceleration for the motion (``set_accel``).
  ``AccelRamp`` / ``DecelRamp`` (jerk limits, s) and ``Speed2`` are kept but
  do not shape the twin's trajectories.
* ``Profile.InRange``: < 0 the motion may blend into the next one (the next
  motion is issued with the controller's CP on); 0 (default) it stops at its
  destination, no settling
  check; > 0 the robot must also settle within the controller's FINE
  tolerance before the next motion starts or ``WaitForEOM`` returns (the
  value itself is not a distance in the twin).
* Motions are queued one deep, as in the V+ forward processing the controller
  implements: ``Move.Loc`` returns at once while the robot is idle, and waits
  for the motion in progress otherwise.
* Preconditions (L1954-1959): high power on, robot homed, robot attached to the
  calling thread; each violation raises its error (codes.py).
"""

from __future__ import annotations

import numpy as np

from ....controller.location import Location
from ....errors import ProgramError
from . import codes
from . import gpl_class, shared
from .members import stored
from .conveyor import belt_target
from .locations import ANGLES, GplLocation, location_arg
from .args import number
from .state import flange_pose, flange_target, from_gpl_angles, joint_of_axis, matrix_m, righty_of, robot_state

def _percent(name: str, zero: bool = False):
    """A percentage property; `zero`: 0 is allowed too (Speed2 = 0: no secondary speed)."""
    def get(self) -> float:
        return self._values[name]

    def put(self, value) -> None:
        value = number(value)
        if not (0.0 <= value if zero else 0.0 < value) or value > 100.0:
            low = "0 <=" if zero else "0 <"
            raise codes.fail(codes.INVALID_ARGUMENT, f"Profile.{name} = {value:g} ({low} percent <= 100)")
        self._values[name] = value

    return property(get, put)


def _seconds(name: str):
    def get(self) -> float:
        return self._values[name]

    def put(self, value) -> None:
        value = float(value)
        if value < 0.0:
            raise codes.fail(codes.INVALID_ARGUMENT, f"Profile.{name} = {value:g} (seconds >= 0)")
        self._values[name] = value

    return property(get, put)


@gpl_class("Profile")
class GplProfile:
    """A GPL motion profile.  Defaults (the manual gives none): full speed,
    acceleration and deceleration, no ramps, joint-interpolated, InRange 0."""

    def __init__(self, rt, *args):
        if args:
            raise codes.fail(codes.INVALID_ARGUMENT, "New Profile takes no arguments")
        self._rt = rt
        self._values = {"Speed": 100.0, "Speed2": 100.0, "Accel": 100.0, "Decel": 100.0,
                        "AccelRamp": 0.0, "DecelRamp": 0.0, "InRange": 0.0}
        self._straight = False
        self._text = ""

    Speed = _percent("Speed")
    Speed2 = _percent("Speed2", zero=True)
    Accel = _percent("Accel")
    Decel = _percent("Decel")
    AccelRamp = _seconds("AccelRamp")
    DecelRamp = _seconds("DecelRamp")

    @property
    def InRange(self) -> float:
        return self._values["InRange"]

    @InRange.setter
    def InRange(self, value) -> None:
        self._values["InRange"] = float(value)

    Straight = stored("_straight", bool)
    Text = stored("_text", str)

    def Clone(self) -> "GplProfile":
        copy = GplProfile(self._rt)
        copy._values = dict(self._values)
        copy._straight, copy._text = self._straight, self._text
        return copy


def profile_arg(value) -> GplProfile:
    return codes.object_arg(value, GplProfile, "a Profile")


# ------------------------------------------------------------ shared helpers
def check_ready(rt) -> None:
    """The preconditions of any motion (manual L1954-1959)."""
    state = robot_state(rt)
    if not state.power:
        raise codes.fail(codes.POWER_OFF)
    if not state.homed:
        raise codes.fail(codes.NOT_HOMED)
    if state.attached_by is None or state.attached_by != rt.current_thread():
        raise codes.fail(codes.NO_ROBOT_ATTACHED)


def destination_joints(rt) -> np.ndarray:
    """Joints at the destination of the last motion."""
    state = robot_state(rt)
    if state.dest_q is None:
        robot = rt.robot
        state.dest_q = robot.kin.ik(matrix_m(robot.destination()), robot.q_command)
    return state.dest_q


def _start_joints(rt) -> np.ndarray:
    """Joints where the next motion starts (Robot.SourceAngles): the last destination's; a
    destination on a moving belt has none fixed, so the joints commanded now."""
    if isinstance(rt.robot.destination(), Location):
        return np.array(destination_joints(rt))
    return np.array(rt.robot.q_command)


def _settle(rt):
    try:
        yield from rt.robot.wait_stopped()
    except ProgramError as err:
        raise codes.from_controller(err) from None


def _go(rt, flange, profile: GplProfile, righty: bool | None, dest_q: np.ndarray | None = None):
    """Start one motion of the flange to `flange` (a Location, robot base frame, or joint
    values in the controller's units) with `profile`."""
    profile = profile_arg(profile)
    check_ready(rt)
    state = robot_state(rt)
    robot = rt.robot
    if state.last_in_range > 0:
        yield from _settle(rt)
    source, source_q = robot.destination(), _start_joints(rt)
    robot.set_speed(profile.Speed)  # this motion only
    if righty is not None and not profile.Straight:  # a straight line keeps the configuration
        robot.request_configuration(righty)
    robot.set_accel(profile.Accel, profile.Decel)
    try:
        # Blend into this motion only when the previous one was not to stop (its InRange < 0).
        yield from robot.move(flange, straight=profile.Straight, cp=state.last_in_range < 0)
    except ProgramError as err:
        raise codes.from_controller(err) from None
    state.source, state.source_q = source, source_q
    state.dest_q = dest_q
    state.last_profile = profile.Clone()
    state.last_in_range = profile.InRange


def _go_joints(rt, q: np.ndarray, profile):
    """A motion to a joint vector: the flange pose there, in that arm configuration."""
    kin = rt.robot.kin
    if not kin.within_limits(q):
        bad = int(np.nonzero((q < kin.lower - 1e-9) | (q > kin.upper + 1e-9))[0][0]) + 1
        raise codes.fail(codes.JOINT_OUT_OF_RANGE, f"axis {bad}")
    # A rail is not determined by the flange pose (the arm's inverse kinematics keeps it
    # still): with one, the controller gets the joints themselves.
    target = rt.robot.to_user_joints(q) if kin.rail is not None else flange_pose(rt, q)
    yield from _go(rt, target, profile, kin.is_righty(q), dest_q=np.array(q))


def _go_location(rt, loc: GplLocation, profile):
    conveyor = loc.on_conveyor()
    if conveyor is not None:  # the robot follows the belt (twin/controller/tracking.py)
        yield from _go(rt, belt_target(rt, conveyor, loc.PosWrtRef.total()), profile, None)
    elif loc.Type == ANGLES:
        yield from _go_joints(rt, from_gpl_angles(rt, loc.joint_values()), profile)
    else:
        yield from _go(rt, flange_target(rt, loc.total()), profile, righty_of(loc.Config))


@gpl_class("Move")
class Move:
    """The global Move class: shared members only."""

    @shared
    def Loc(rt, loc, profile):
        """Move to the total position of `loc` (L1946)."""
        yield from _go_location(rt, location_arg(loc), profile)

    @shared
    def Approach(rt, loc, profile):
        """Move to the clearance position of a Cartesian `loc` (ZClearance, ZWorld)."""
        loc = location_arg(loc)
        conveyor = loc.on_conveyor()
        if conveyor is not None:  # the clearance point rides on the belt too
            frame_total = loc.RefFrame.total()
            yield from _go(rt, belt_target(rt, conveyor, frame_total.inverse() * loc.clearance()), profile, None)
            return
        yield from _go(rt, flange_target(rt, loc.clearance()), profile, righty_of(loc.Config))

    @shared
    def Rel(rt, loc, profile):
        """Move relative to the previous motion's destination: Cartesian offsets are in the
        destination's tool frame (Dest * loc), Angles offsets are added axis by axis."""
        loc = location_arg(loc)
        if loc.Type == ANGLES:
            q = destination_joints(rt) + from_gpl_angles(rt, loc.joint_values())
            yield from _go_joints(rt, q, profile)
        else:
            dest = robot_state(rt).base * rt.robot.destination() * robot_state(rt).tool
            yield from _go(rt, flange_target(rt, dest * loc.total()), profile, None)

    @shared
    def OneAxis(rt, axis, position, relative, profile):
        """Move one axis (1-based) to `position` (degrees or mm), or by it when `relative`."""
        q = destination_joints(rt).copy()
        n = int(axis)
        joint = joint_of_axis(rt, n)
        if joint is None:
            raise codes.fail(codes.INVALID_ARGUMENT, f"axis {axis}")
        value = from_gpl_angles(rt, [0.0] * (n - 1) + [float(position)])[joint]
        q[joint] = q[joint] + value if relative else value
        yield from _go_joints(rt, q, profile)

    @shared
    def Delay(rt, seconds):
        """Pause the motion queue (not the thread) for `seconds`."""
        check_ready(rt)
        seconds = float(seconds)
        if seconds < 0:
            raise codes.fail(codes.INVALID_ARGUMENT, f"Move.Delay({seconds:g})")
        yield from rt.robot.dwell(seconds)

    @shared
    def WaitForEOM(rt):
        """Wait until the motion in progress is complete (settled when its InRange > 0)."""
        robot = rt.robot
        if robot.moving:
            yield lambda: not robot.moving
        if robot_state(rt).last_in_range > 0:
            yield from _settle(rt)

    @shared
    def StopSpecialModes(rt):
        """End any special trajectory mode: the twin has none active, so nothing to stop."""

    Arc = codes.unsupported("Move.Arc", "circular interpolation is not implemented")
    Circle = codes.unsupported("Move.Circle", "circular interpolation is not implemented")
    Extra = codes.unsupported("Move.Extra", "the cell has no extra axes")
    ForceOverlap = codes.unsupported("Move.ForceOverlap", "the twin does not blend motions")
    SetJogCommand = codes.unsupported("Move.SetJogCommand", "jog mode needs a pendant")
    StartJogMode = codes.unsupported("Move.StartJogMode", "jog mode needs a pendant")
    SetRealTimeMod = codes.unsupported("Move.SetRealTimeMod", "real-time path modification")
    StartRealTimeMod = codes.unsupported("Move.StartRealTimeMod", "real-time path modification")
    SetSpeeds = codes.unsupported("Move.SetSpeeds", "velocity control mode")
    StartVelocityCntrl = codes.unsupported("Move.StartVelocityCntrl", "velocity control mode")
    SetTorques = codes.unsupported("Move.SetTorques", "torque control mode")
    StartTorqueCntrl = codes.unsupported("Move.StartTorqueCntrl", "torque control mode")
    StartSpeedDAC = codes.unsupported("Move.StartSpeedDAC", "the cell has no analog outputs")
    Trigger = codes.unsupported("Move.Trigger", "motion triggers are not implemented")

