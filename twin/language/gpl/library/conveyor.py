"""GPL conveyor tracking: conveyor RefFrames (Type 2) and the Latch class (User Manual
ch. 12, "Conveyor Reference Frame", "Latch Class"), on the controller's belt frames
(twin/controller/belt.py), the same physical belts and encoders V+ uses.

Decisions (docs/gpl.md, "Conveyor tracking"):
* A conveyor is an encoder-only robot: robot n + 1 reads belt encoder n (robot 1 is
  the arm).  Its "angle" is the belt position in mm (counts / counts per mm).
* Its nominal transformation (PosWrtRef) is the conveyor's frame from the scene: the
  centre of the belt's top face, X along the travel, in the robot's world (Robot.Base
  applied).  ConveyorOffset is the belt position (mm) at which the frame is nominal.
* Its limits (Location.ConveyorLimit, the tracking window) are the stretch of the belt
  the arm can reach with the tool pointing down (its floor plan at the arm's height).
"""

from __future__ import annotations

import weakref

import numpy as np

from ....controller.belt import BeltFrame, BeltLocation, BeltWindow, conveyor_nominal
from ....controller.kinematics import KinematicsError
from ....controller.location import Location, trans
from . import codes, gpl_class, shared
from .state import check_robot, robot_state

ARM = 1
REACH_STEP_MM = 5.0  # sampling of the belt line for the reachable stretch
REACH_SPAN_MM = 3000.0  # searched each side of the belt frame's origin


def encoder_of(rt, robot):
    """The encoder an encoder-only robot (a conveyor) reads."""
    n = int(robot)
    encoders = getattr(rt.robot.cell, "encoders", None) or {}
    if n == ARM:
        return None
    if n - 1 not in encoders:
        raise codes.fail(codes.INVALID_ROBOT, f"{n}: no conveyor robot (the cell's belt encoders are "
                                              f"robots {[k + 1 for k in sorted(encoders)] or 'none'})")
    return encoders[n - 1]


_REACH: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()  # controller -> {nominal: window}


def _reachable(rt, nominal: Location) -> BeltWindow:
    """The stretch of the belt's X axis the arm reaches, tool down (see the module doc)."""
    cached = _REACH.setdefault(rt.robot, {})
    key = nominal.components()
    if key in cached:
        return cached[key]
    kin, robot = rt.robot.kin, rt.robot
    height = kin.fk(robot.q_command)[2, 3] * 1000.0  # reach across the floor plan, at the arm's height now
    inside = []
    for x in np.arange(-REACH_SPAN_MM, REACH_SPAN_MM + REACH_STEP_MM, REACH_STEP_MM):
        x_mm, y_mm, _ = (nominal * trans(float(x))).position()
        try:
            kin.ik(robot._flange_matrix_m(Location(x_mm, y_mm, height, 0.0, 180.0, 0.0)), robot.q_command)
        except KinematicsError:
            continue
        inside.append(float(x))
    if not inside:
        raise codes.fail(codes.LOCATION_OUT_OF_RANGE, "the arm reaches no part of the conveyor")
    window = BeltWindow(min(inside), max(inside))
    cached[key] = window
    return window


class ConveyorFrame:
    """What a Type 2 RefFrame adds: its conveyor robot and the offset."""

    def __init__(self, rt):
        self.rt = rt
        self.robot = 0  # no conveyor robot chosen yet
        self.offset_mm = 0.0
        self._frames: dict = {}

    def belt(self) -> BeltFrame:
        """The controller's belt frame for this RefFrame, in the robot base frame."""
        rt = self.rt
        if self.robot == 0:
            raise codes.fail(codes.INVALID_ROBOT, "RefFrame.ConveyorRobot is not set")
        encoder = encoder_of(rt, self.robot)
        nominal = conveyor_nominal(rt.robot.cell, encoder.number)
        if nominal is None:
            raise codes.fail(codes.INVALID_ROBOT, f"{self.robot}: encoder {encoder.number} is on no conveyor")
        belt = self._frames.get(self.robot)
        if belt is None:
            belt = BeltFrame(nominal, encoder, 1.0 / encoder.counts_per_mm, name=f"conveyor robot {self.robot}")
            belt.speed_source = rt.robot.belts.speed_of
            belt.window = _reachable(rt, nominal)
            rt.robot.belts.show_window(belt)
            self._frames[self.robot] = belt
        belt.offset = round(self.offset_mm * encoder.counts_per_mm)
        return belt

    def nominal(self) -> Location:
        """PosWrtRef: the nominal transformation, in the GPL world (Robot.Base applied)."""
        return robot_state(self.rt).base * self.belt().nominal

    def total(self) -> Location:
        """Pos: where the belt frame is now, in the GPL world."""
        return robot_state(self.rt).base * self.belt().instantaneous()


def belt_target(rt, frame: ConveyorFrame, pose: Location) -> BeltLocation:
    """The flange target for a tool-tip pose relative to a conveyor frame (controller
    frames: the belt in the robot base frame, the tool taken off on the belt)."""
    state = robot_state(rt)
    return BeltLocation(frame.belt(), pose * state.tool.inverse())


def conveyor_limit(frame: ConveyorFrame, pose: Location, mode) -> float:
    """Location.ConveyorLimit(mode): mm to the downstream limit (mode 0, negative past it)
    or past the upstream limit (mode 1, negative before it); both positive inside."""
    to_downstream, past_upstream = frame.belt().window_distances(pose)
    return past_upstream if int(mode or 0) > 0 else to_downstream


@gpl_class("Latch")
class GplLatch:
    """One latch result (Latch.Result): the time and the belt position it captured."""

    def __init__(self, rt, *args):
        raise codes.fail(codes.INVALID_ARGUMENT, "Latch objects come from Latch.Result")

    @classmethod
    def of(cls, rt, encoder, when: float, count: int, signal) -> "GplLatch":
        latch = cls.__new__(cls)
        latch._rt, latch._time, latch._signal = rt, float(when), signal
        latch._position = count / encoder.counts_per_mm
        return latch

    def Angle(self, axis=1) -> float:
        """The latched belt position (mm): a conveyor robot has one axis."""
        if int(axis) != 1:
            raise codes.fail(codes.INVALID_ARGUMENT, f"axis {axis}: a conveyor robot has axis 1 only")
        return self._position

    @property
    def ErrorCode(self) -> int:
        return 0

    def Location(self):
        from .locations import GplLocation
        return GplLocation.angles(self._rt, [self._position])

    @property
    def RawTime(self) -> float:
        return self._time

    @property
    def Signal(self) -> int:
        return 0 if self._signal is None else int(self._signal)

    @property
    def Timestamp(self) -> float:
        return self._time

    @shared
    def Count(rt, robot=ARM) -> int:
        encoder = _latching(rt, robot)
        return 0 if encoder is None else len(encoder.latches)

    @shared
    def Flush(rt, robot=ARM) -> None:
        encoder = _latching(rt, robot)
        if encoder is not None:
            encoder.latches.clear()

    @shared
    def Result(rt, robot=ARM):
        """The oldest latch result of the robot or belt, removed from its queue; Nothing
        when the queue is empty."""
        encoder = _latching(rt, robot)
        if encoder is None or not encoder.latches:
            return None
        when, count = encoder.latches.popleft()
        return GplLatch.of(rt, encoder, when, count, encoder.latch_input)

    ThreadEvent = codes.unsupported("Latch.ThreadEvent", "latch thread events are not implemented")


def _latching(rt, robot):
    """The encoder of a conveyor robot; None for the arm (it has no latch input wired)."""
    if int(robot) == ARM:
        check_robot(robot)
        return None
    return encoder_of(rt, robot)
