"""GPL Location and RefFrame objects (User Manual ch. 12, L1824-1915, L1994-2088).

A Cartesian Location stores its pose relative to its optional RefFrame
(PosWrtRef) as a twin Location (x, y, z mm; yaw, pitch, roll deg; Z-Y'-Z''
Euler angles, the convention of manual L1865, the same as V+).  Its "total
position" (Pos) is the frame's total pose composed with PosWrtRef (L1853).
An Angles Location stores one value per robot axis (degrees or mm).

Decisions (docs/gpl.md, "Built-in classes"):
* ``New Location`` is Cartesian at all zeros; setting ``Type`` keeps nothing of
  the old data (the values become zeros of the new type); conversion between
  the types is ``Kinesol``.
* Cartesian-only members on an Angles location raise -762, ``Angle`` on a
  Cartesian one -763.
* Approach point (Move.Approach): with ``ZWorld`` True the total position raised
  by ZClearance along world +Z; with ZWorld False (default) ZClearance back
  along the location's own tool Z, ``Pos * Trans(0, 0, -ZClearance)`` (like V+
  APPRO), which is above the part for a tool pointing down (pitch 180).  A new
  Location's ZClearance is 1E+32, "not set": Move.Approach to it is -794.
* Pallet frames step along Loc's X (rows), Y (columns), Z (layers); PalletOrder
  0-5 is the GPL Dictionary's code of the stepping order, default 0 (row first).
"""

from __future__ import annotations

import numpy as np

from ....controller.location import NULL, Location, trans
from . import codes
from . import gpl_class, shared
from .args import integer
from .conveyor import ConveyorFrame, conveyor_limit
from .members import stored
from .state import axis_count, from_gpl_angles, solve_joints, to_gpl_angles, tool_pose

CARTESIAN, ANGLES = 0, 1
MAX_AXES = 12
MAX_FRAME_DEPTH = 32
# RefFrame.PalletOrder (GPL Dictionary): the dimensions (0 row, 1 column, 2 layer) in the
# order PalletNextPos increments them; 0 (row, column, layer) is a new pallet's.
PALLET_ORDERS = ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0))
NO_CLEARANCE = 1e32  # a new Location's ZClearance: what GDE-generated .gpo files write for "not set" (digest §8.2)
UNSET_CLEARANCE = 1e30  # from here up a ZClearance is "not set" (the TCP Command Server 3.0 tests > 1E30)


def _number(value) -> float:
    return float(value)


@gpl_class("Location")
class GplLocation:
    """A GPL Location object."""

    def __init__(self, rt, *args):
        if args:
            raise codes.fail(codes.INVALID_ARGUMENT, "New Location takes no arguments")
        self._rt = rt
        self._type = CARTESIAN
        self._pose = NULL
        self._angles = [0.0] * MAX_AXES
        self._frame: GplRefFrame | None = None
        self._config = 0
        self._text = ""
        self._zclearance = NO_CLEARANCE
        self._zworld = False

    @classmethod
    def cartesian(cls, rt, pose: Location) -> "GplLocation":
        loc = cls(rt)
        loc._pose = pose
        return loc

    @classmethod
    def angles(cls, rt, values) -> "GplLocation":
        loc = cls(rt)
        loc._type = ANGLES
        loc._angles[: len(values)] = [float(v) for v in values]
        return loc

    def __repr__(self) -> str:
        if self._type == ANGLES:
            return f"Location(angles {self._angles[: axis_count(self._rt)]})"
        return f"Location{self._pose.components()}"

    # ------------------------------------------------------------ checks
    def _cartesian(self) -> None:
        if self._type != CARTESIAN:
            raise codes.fail(codes.NOT_CARTESIAN, "needs a Cartesian Location")

    def _angles_type(self) -> None:
        if self._type != ANGLES:
            raise codes.fail(codes.NOT_ANGLES, "needs an Angles Location")

    # ------------------------------------------------------------ poses
    def total(self) -> Location:
        """Total position of a Cartesian location (frame chain composed)."""
        self._cartesian()
        if self._frame is None:
            return self._pose
        return self._frame.total() * self._pose

    def joint_values(self) -> list[float]:
        """Axis values of an Angles location, one per robot axis."""
        self._angles_type()
        return self._angles[: axis_count(self._rt)]

    def _set_total(self, pose: Location) -> None:
        self._pose = pose if self._frame is None else self._frame.total().inverse() * pose

    # ------------------------------------------------------------ properties
    @property
    def Type(self) -> int:
        return self._type

    @Type.setter
    def Type(self, value) -> None:
        value = int(value)
        if value not in (CARTESIAN, ANGLES):
            raise codes.fail(codes.INVALID_ARGUMENT, f"Location.Type {value}")
        if value != self._type:
            self._type = value
            self._pose = NULL
            self._angles = [0.0] * MAX_AXES
            self._frame = None

    def _component(self, index: int) -> float:
        self._cartesian()
        return self._pose.components()[index]

    def _set_component(self, index: int, value) -> None:
        self._cartesian()
        values = list(self._pose.components())
        values[index] = _number(value)
        self._pose = Location(*values)

    X = property(lambda self: self._component(0), lambda self, v: self._set_component(0, v))
    Y = property(lambda self: self._component(1), lambda self, v: self._set_component(1, v))
    Z = property(lambda self: self._component(2), lambda self, v: self._set_component(2, v))
    Yaw = property(lambda self: self._component(3), lambda self, v: self._set_component(3, v))
    Pitch = property(lambda self: self._component(4), lambda self, v: self._set_component(4, v))
    Roll = property(lambda self: self._component(5), lambda self, v: self._set_component(5, v))

    @property
    def Pos(self) -> "GplLocation":
        """The total position as a new Location (Cartesian without frame, or Angles)."""
        if self._type == ANGLES:
            return GplLocation.angles(self._rt, self.joint_values())
        return GplLocation.cartesian(self._rt, self.total())

    @Pos.setter
    def Pos(self, value: "GplLocation") -> None:
        """The total position becomes the value's; the location takes the value's type
        (field code assigns a Cartesian Pos to an Angles location, and the reverse)."""
        value = location_arg(value)
        if value._type == ANGLES:
            self.Angles(*value._angles)
            return
        if self._type == ANGLES:
            self.Type = CARTESIAN
        self._set_total(value.total())

    @property
    def PosWrtRef(self) -> "GplLocation":
        self._cartesian()
        return GplLocation.cartesian(self._rt, self._pose)

    @PosWrtRef.setter
    def PosWrtRef(self, value: "GplLocation") -> None:
        self._cartesian()
        self._pose = location_arg(value).total()

    @property
    def RefFrame(self):
        return self._frame

    @RefFrame.setter
    def RefFrame(self, frame) -> None:
        self._cartesian()
        if frame is not None and not isinstance(frame, GplRefFrame):
            raise codes.fail(codes.INVALID_ARGUMENT, "RefFrame must be a RefFrame object")
        self._frame = frame
        if frame is not None:
            frame.total()  # a loop through this location's frame chain is an error now

    Config = stored("_config", int)
    Text = stored("_text", str)
    ZClearance = stored("_zclearance", _number)
    ZWorld = stored("_zworld", bool)

    # ------------------------------------------------------------ Angles members
    def Angle(self, axis) -> float:
        self._angles_type()
        return self._angles[_axis_index(axis)]

    def set_Angle(self, axis, value) -> None:
        self._angles_type()
        self._angles[_axis_index(axis)] = _number(value)

    def Angles(self, *values) -> None:
        """Set the axis values, one per robot axis (GPL Dictionary: the location becomes an
        Angles location); an axis not given is 0."""
        if self._type != ANGLES:
            self.Type = ANGLES
        if len(values) > MAX_AXES:
            raise codes.fail(codes.INVALID_ARGUMENT, f"more than {MAX_AXES} axis values")
        self._angles = [_number(v) for v in values] + [0.0] * (MAX_AXES - len(values))

    # ------------------------------------------------------------ methods
    def Clone(self) -> "GplLocation":
        copy = GplLocation(self._rt)
        copy.__dict__.update(self.__dict__)
        copy._angles = list(self._angles)
        return copy

    @shared
    def Distance(rt, a: "GplLocation", b: "GplLocation") -> float:
        """Distance (mm) between the XYZ of the total positions of two Cartesian locations."""
        return float(np.linalg.norm(location_arg(a).total().position() - location_arg(b).total().position()))

    def Here(self) -> None:
        """Set the total position to where the (selected) robot is now (L1897)."""
        q = self._rt.robot.joints()
        if self._type == ANGLES:
            self.Angles(*to_gpl_angles(self._rt, q))
        else:
            self._set_total(tool_pose(self._rt, q))

    def Here3(self, origin: "GplLocation", on_x: "GplLocation", in_xy: "GplLocation") -> None:
        """Total position from three points: the origin, a point on +X, a point in the XY plane."""
        self._cartesian()
        p0, px, pxy = (location_arg(v).total().position() for v in (origin, on_x, in_xy))
        x = px - p0
        z = np.cross(x, pxy - p0)
        if np.linalg.norm(x) < 1e-9 or np.linalg.norm(z) < 1e-9:
            raise codes.fail(codes.INVALID_ARGUMENT, "Here3 points are collinear")
        x /= np.linalg.norm(x)
        z /= np.linalg.norm(z)
        T = np.eye(4)
        T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, np.cross(z, x), z, p0
        self._set_total(Location.from_matrix(T))

    def Inverse(self) -> "GplLocation":
        return GplLocation.cartesian(self._rt, self.total().inverse())

    def Kinesol(self, *ignored) -> "GplLocation":
        """Angles -> Cartesian (forward kinematics, Robot.Base and Tool applied) or
        Cartesian -> Angles (inverse kinematics seeded at the present joints, arm
        configuration from Config if it asks for one).  The arguments (kinematic
        model selection) are accepted and ignored: the twin has one robot model."""
        rt = self._rt
        if self._type == ANGLES:
            return GplLocation.cartesian(rt, tool_pose(rt, from_gpl_angles(rt, self.joint_values())))
        return GplLocation.angles(rt, to_gpl_angles(rt, solve_joints(rt, self.total(), self._config)))

    def Mul(self, other: "GplLocation") -> "GplLocation":
        """total(self) composed with total(other): other expressed in self's frame (L1875)."""
        return GplLocation.cartesian(self._rt, self.total() * location_arg(other).total())

    def Normalize(self) -> None:
        """Re-orthonormalise PosWrtRef's rotation (the twin's poses are always orthonormal:
        they are stored as angles, so this only rebuilds the same pose)."""
        self._cartesian()
        self._pose = Location.from_matrix(self._pose.matrix())

    def XYZ(self, x=0.0, y=0.0, z=0.0, yaw=0.0, pitch=0.0, roll=0.0) -> None:
        self._cartesian()
        self._pose = trans(*(_number(v) for v in (x, y, z, yaw, pitch, roll)))

    def XYZInc(self, dx=0.0, dy=0.0, dz=0.0) -> None:
        self._cartesian()
        self._pose = self._pose.shifted(_number(dx), _number(dy), _number(dz))

    @shared
    def XYZValue(rt, x=0.0, y=0.0, z=0.0, yaw=0.0, pitch=0.0, roll=0.0) -> "GplLocation":
        return GplLocation.cartesian(rt, trans(*(_number(v) for v in (x, y, z, yaw, pitch, roll))))

    def ConveyorLimit(self, mode=0) -> float:
        """mm to the conveyor's downstream limit (mode 0) or past its upstream limit (mode
        1), both positive inside the limits (docs/gpl.md, "Conveyor tracking")."""
        self._cartesian()
        conveyor = None if self._frame is None else self._frame.conveyor
        if conveyor is None:
            raise codes.fail(codes.INVALID_ARGUMENT, "ConveyorLimit needs a Location relative to a conveyor RefFrame")
        return conveyor_limit(conveyor, self._pose, mode)

    def on_conveyor(self) -> ConveyorFrame | None:
        """The conveyor frame this Cartesian location is relative to, if any."""
        return None if self._type != CARTESIAN or self._frame is None else self._frame.conveyor

    # ------------------------------------------------------------ motion helpers
    def clearance(self) -> Location:
        """The approach position of a Cartesian location (see the module docstring)."""
        pose = self.total()
        if self._zclearance >= UNSET_CLEARANCE:  # Brooks error list -794: "set to a very large number"
            raise codes.fail(codes.ZCLEARANCE_NOT_SET)
        if self._zworld:
            return pose.shifted(dz=self._zclearance)
        return pose * trans(z=-self._zclearance)


def _axis_index(axis) -> int:
    n = int(axis)
    if not 1 <= n <= MAX_AXES:
        raise codes.fail(codes.INVALID_ARGUMENT, f"axis {axis}")
    return n - 1


def location_arg(value) -> GplLocation:
    return codes.object_arg(value, GplLocation, "a Location")



@gpl_class("RefFrame")
class GplRefFrame:
    """A GPL reference frame: basic (Type 0), pallet (Type 1) or conveyor (Type 2: its
    position moves with the belt, conveyor.py)."""

    def __init__(self, rt, *args):
        if args:
            raise codes.fail(codes.INVALID_ARGUMENT, "New RefFrame takes no arguments")
        self._rt = rt
        self._type = 0
        self._loc = GplLocation(rt)
        self._text = ""
        self._index = [1, 1, 1]
        self._max_index = [1, 1, 1]
        self._pitch = [0.0, 0.0, 0.0]
        self._order = 0
        self.conveyor: ConveyorFrame | None = None

    @property
    def Type(self) -> int:
        return self._type

    @Type.setter
    def Type(self, value) -> None:
        value = int(value)
        if value not in (0, 1, 2):
            raise codes.fail(codes.INVALID_ARGUMENT, f"RefFrame.Type {value}")
        self._type = value
        self.conveyor = ConveyorFrame(self._rt) if value == 2 else None

    @property
    def Loc(self) -> GplLocation:
        return self._loc

    @Loc.setter
    def Loc(self, value) -> None:
        self._loc = location_arg(value)
        self.total()

    Text = stored("_text", str)

    def total(self, depth: int = 0) -> Location:
        """The frame's total (absolute) pose."""
        if depth > MAX_FRAME_DEPTH:
            raise codes.fail(codes.FRAME_LOOP)
        if self.conveyor is not None:  # the belt's instantaneous position; Loc is not used
            return self.conveyor.total()
        loc = self._loc
        loc._cartesian()
        base = loc._pose if loc._frame is None else loc._frame.total(depth + 1) * loc._pose
        return base * self._pallet_offset()

    def _pallet_offset(self) -> Location:
        if self._type != 1:
            return NULL
        d = [(i - 1) * p for i, p in zip(self._index, self._pitch)]
        return trans(*d)

    def Pos(self) -> GplLocation:
        return GplLocation.cartesian(self._rt, self.total())

    def PosWrtRef(self) -> GplLocation:
        if self.conveyor is not None:  # the conveyor's nominal transformation
            return GplLocation.cartesian(self._rt, self.conveyor.nominal())
        self._loc._cartesian()
        return GplLocation.cartesian(self._rt, self._loc._pose * self._pallet_offset())

    def Clone(self) -> "GplRefFrame":
        copy = GplRefFrame(self._rt)
        copy.__dict__.update(self.__dict__)
        copy._loc = self._loc.Clone()
        copy._index, copy._max_index, copy._pitch = list(self._index), list(self._max_index), list(self._pitch)
        if self.conveyor is not None:
            copy.conveyor = ConveyorFrame(self._rt)
            copy.conveyor.robot, copy.conveyor.offset_mm = self.conveyor.robot, self.conveyor.offset_mm
        return copy

    # ------------------------------------------------------------ pallet members
    def _pallet(self) -> None:
        if self._type != 1:
            raise codes.fail(codes.INVALID_ARGUMENT, "not a pallet reference frame (Type 1)")

    def PalletIndex(self, dim) -> int:
        self._pallet()
        return self._index[_dim(dim)]

    def set_PalletIndex(self, dim, value) -> None:
        self._pallet()
        d = _dim(dim)
        value = int(value)
        if not 1 <= value <= self._max_index[d]:
            raise codes.fail(codes.INVALID_ARGUMENT, f"PalletIndex({dim}) = {value}")
        self._index[d] = value

    def PalletMaxIndex(self, dim) -> int:
        self._pallet()
        return self._max_index[_dim(dim)]

    def set_PalletMaxIndex(self, dim, value) -> None:
        self._pallet()
        d = _dim(dim)
        value = int(value)
        if value < 1:
            raise codes.fail(codes.INVALID_ARGUMENT, f"PalletMaxIndex({dim}) = {value}")
        self._max_index[d] = value
        self._index[d] = min(self._index[d], value)

    def PalletPitch(self, dim) -> float:
        self._pallet()
        return self._pitch[_dim(dim)]

    def set_PalletPitch(self, dim, value) -> None:
        self._pallet()
        self._pitch[_dim(dim)] = _number(value)

    @property
    def PalletOrder(self) -> int:
        return self._order

    @PalletOrder.setter
    def PalletOrder(self, value) -> None:
        value = integer(value)
        if not 0 <= value < len(PALLET_ORDERS):
            raise codes.fail(codes.INVALID_ARGUMENT, f"PalletOrder {value} (0 to 5)")
        self._order = value

    def PalletNextPos(self) -> None:
        """Advance to the next element; after the last one wrap to the first (L2060)."""
        self._pallet()
        for d in PALLET_ORDERS[self._order]:
            if self._index[d] < self._max_index[d]:
                self._index[d] += 1
                return
            self._index[d] = 1

    def PalletRowColLay(self, row, column, layer=1) -> None:
        for dim, value in ((1, row), (2, column), (3, layer)):
            self.set_PalletIndex(dim, value)

    # ------------------------------------------------------------ conveyor members
    def _on_conveyor(self) -> ConveyorFrame:
        if self.conveyor is None:
            raise codes.fail(codes.INVALID_ARGUMENT, "not a conveyor reference frame (Type 2)")
        return self.conveyor

    @property
    def ConveyorOffset(self) -> float:
        return self._on_conveyor().offset_mm

    @ConveyorOffset.setter
    def ConveyorOffset(self, value) -> None:
        self._on_conveyor().offset_mm = _number(value)

    @property
    def ConveyorRobot(self) -> int:
        return self._on_conveyor().robot

    @ConveyorRobot.setter
    def ConveyorRobot(self, value) -> None:
        conveyor = self._on_conveyor()
        conveyor.robot = int(value)
        conveyor.belt()  # a robot that is no conveyor is an error here


def _dim(dim) -> int:
    d = int(dim)
    if d not in (1, 2, 3):
        raise codes.fail(codes.INVALID_ARGUMENT, f"pallet dimension {dim} (1 row, 2 column, 3 layer)")
    return d - 1

