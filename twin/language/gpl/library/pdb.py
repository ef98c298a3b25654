"""The configuration parameter database as GPL sees it: ``Controller.PDb`` (any value,
as a String) and ``Controller.PDbNum`` (numeric values, as a Double).

Signatures (GPL Dictionary, Controller.PDb / Controller.PDbNum):
``PDb(dataid, unit, unit2, array_index, key)``: unit and unit2 default to 1;
array_index defaults to 0 for PDb (all the values, comma separated) and to 1 for
PDbNum (the first value); key (protection override) is accepted and ignored.

Only the DataIDs below exist in the twin; any other one is the controller's
error for an undefined DataID.  Each entry says where its number comes from
(the User Manual's lines, or the public Parameter Database reference).  The
robot entries (2000-3999, 16000-17999) belong to robot `unit`: the twin has
robot 1 only.  docs/gpl.md lists them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from . import codes
from .args import integer, number, text
from .state import check_robot, robot_state

READ_ONLY, READ_WRITE = True, False


@dataclass(frozen=True)
class Entry:
    label: str
    kind: str  # "num", "int", "bool" or "str"
    count: int  # values in the array (1: a scalar)
    default: Callable[[Any], list]  # rt -> the values at boot
    read_only: bool = False
    robot: bool = False  # a robot parameter (unit = robot number)
    live: bool = False  # a state, read anew each time (not a setting kept from boot)


def _const(*values) -> Callable[[Any], list]:
    return lambda rt: list(values)


def _axes(rt) -> int:
    from .state import axis_count  # noqa: PLC0415 - as _soft_limits
    return axis_count(rt)


def _power_state(rt) -> int:
    from .robot import power_state  # noqa: PLC0415 - robot imports this module
    return power_state(rt)


def _axis_mask(rt) -> int:
    """Bit n-1 for each axis n the robot has (a PF400 on a rail: axes 1-4 and 6)."""
    return sum(1 << (axis - 1) for axis in rt.robot.kin.axis_numbers)


def _link_lengths(rt) -> list:
    """A SCARA's inner and outer link lengths (mm) in slots 2 and 3, as a PF400's controller
    lists them (0, 302, 289, 0, ...: a field unit's calib01.pac); zeros for other robots."""
    values = [0.0] * 16
    scara = rt.robot.kin.scara
    if scara is not None:
        values[1], values[2] = round(scara.l1 * 1000.0, 6), round(scara.l2 * 1000.0, 6)
    return values


def _soft_limits(which: int) -> Callable[[Any], list]:
    """Joint soft limits in GPL units (degrees, mm) from the robot model."""
    def limits(rt) -> list:
        from .state import to_gpl_angles  # noqa: PLC0415 - state imports numpy arrays of the model
        kin = rt.robot.kin
        # Rounded to a micro-unit: the model stores radians, the database degrees.
        return [round(v, 6) for v in to_gpl_angles(rt, kin.upper if which > 0 else kin.lower)]
    return limits


def _mounted_tool(rt) -> list:
    """The restart tool of the gripper the cell mounts: its TCP in the flange frame (mm), as
    the integrator configures the controller for its tool; none (zeros) without a cell."""
    cell = getattr(rt.robot, "cell", None)
    if cell is None or not hasattr(cell, "tcp_position"):
        return [0.0] * 6
    flange = cell.robot_base_pose() @ rt.robot.kin.fk(cell.robot_qpos())
    tcp = np.linalg.solve(flange, np.append(cell.tcp_position(), 1.0))[:3] * 1000.0
    return [float(v) for v in np.round(tcp, 3)] + [0.0, 0.0, 0.0]


# DataID -> entry.  Sources: "manual Lnnn" (gpl-user-manual.txt), "PDB" (the public Parameter
# Database reference, www2.brooksautomation.com/Controller_Software/Software_Reference/PDB),
# "Dictionary" (the GPL Dictionary page of Controller.PDb).
TABLE: dict[int, Entry] = {
    100: Entry("Controller manufacturer", "str", 1, _const("Brooks Automation"), READ_ONLY),  # PDB
    101: Entry("Controller model", "str", 1, _const("twin"), READ_ONLY),  # PDB
    103: Entry("Full software version", "str", 1, _const("GPL 4.2 (twin digital twin)"), READ_ONLY),  # PDB
    104: Entry("Software version", "int", 1, _const(4), READ_ONLY),  # PDB
    125: Entry("Serial console enable", "bool", 1, _const(True)),  # manual L2859
    323: Entry("Error log file", "str", 1, _const("")),  # manual L3018
    424: Entry("Vision server IP address", "str", 1, _const("127.0.0.1")),  # manual L3094
    601: Entry("Test speed", "num", 1, _const(10.0)),  # Dictionary ("test speed" is 601)
    **{i: Entry(f"GPL program variable {i - 1849}", "num", 1, _const(0.0)) for i in range(1850, 1870)},  # Dictionary
    1892: Entry("GPL program NVRAM variable array", "int", 8, _const(*[0] * 8)),  # manual L3034
    234: Entry("Power state", "int", 1, lambda rt: [_power_state(rt)], READ_ONLY, live=True),  # PyLabRobot DataIDs
    2000: Entry("Number of axes", "int", 1, lambda rt: [_axes(rt)], READ_ONLY, robot=True),  # PDB
    2002: Entry("Robot Name", "str", 1, _const("Robot 1"), robot=True),  # PDB
    2003: Entry("Axis Mask", "int", 1, lambda rt: [_axis_mask(rt)], READ_ONLY, robot=True),  # PDB
    2800: Entry("Robot homed", "bool", 1, lambda rt: [robot_state(rt).homed], READ_ONLY, robot=True,
                live=True),  # PyLabRobot DataIDs; the AD-SDL PF400 driver reads it
    16000: Entry("Robot serial number", "str", 1, _const("TWIN-0001"), robot=True),  # PDB
    16050: Entry("Kinematic dimensional constants", "num", 16, _link_lengths, READ_ONLY, robot=True),  # PDB
    16051: Entry("Tool set at restart", "num", 6, _mounted_tool, robot=True),  # PDB; the cell's gripper
    16052: Entry("Base set at restart", "num", 6, _const(*[0.0] * 6), robot=True),  # PDB
    16077: Entry("Joint maximum soft stop limits", "num", 0, _soft_limits(+1), READ_ONLY, robot=True),  # Dictionary
    16078: Entry("Joint minimum soft stop limits", "num", 0, _soft_limits(-1), READ_ONLY, robot=True),  # Dictionary
}

_CONVERT = {"num": number, "int": integer, "bool": lambda v: number(v) != 0, "str": text}


@dataclass
class Database:
    """The values of one run's controller, made from TABLE's defaults at first use."""

    values: dict[int, list] = field(default_factory=dict)

    def of(self, rt, dataid: int) -> tuple[Entry, list]:
        entry = TABLE[dataid]
        if dataid not in self.values or entry.live:
            try:
                self.values[dataid] = list(entry.default(rt))
            except AttributeError:  # a value taken from the robot model, in a run without a cell
                raise codes.fail(codes.NOT_SUPPORTED, f"DataID {dataid}: this run has no robot") from None
        return entry, self.values[dataid]


def database(rt) -> Database:
    state = robot_state(rt)
    if state.pdb is None:
        state.pdb = Database()
    return state.pdb


def _lookup(rt, dataid, unit, unit2) -> tuple[Entry, list]:
    dataid, unit, unit2 = integer(dataid), integer(unit), integer(unit2)
    entry = TABLE.get(dataid)
    if entry is None:
        raise codes.fail(codes.UNDEFINED_DATAID, str(dataid))
    if entry.robot:
        check_robot(unit)
    elif unit != 1:
        raise codes.fail(codes.INVALID_ARGUMENT, f"DataID {dataid} has unit 1 only, not {unit}")
    if unit2 != 1:
        raise codes.fail(codes.INVALID_ARGUMENT, f"DataID {dataid}: sub unit {unit2}")
    return database(rt).of(rt, dataid)


def _element(dataid: int, values: list, index: int) -> int:
    if not 1 <= index <= len(values):
        raise codes.fail(codes.INVALID_ARGUMENT, f"DataID {dataid} has {len(values)} value(s), not index {index}")
    return index - 1


def _shown(entry: Entry, value) -> str:
    if entry.kind == "bool":
        return "1" if value else "0"
    if entry.kind == "num":
        from ..values import format_value  # noqa: PLC0415 - the interpreter's number format
        return format_value(float(value))
    return str(value)


def read(rt, dataid, unit, unit2, index, numeric: bool):
    entry, values = _lookup(rt, dataid, unit, unit2)
    index = integer(index)
    if numeric and entry.kind == "str":
        raise codes.fail(codes.INVALID_ARGUMENT, f"DataID {integer(dataid)} ({entry.label}) is not numeric")
    if index == 0 and not numeric:
        return ",".join(_shown(entry, v) for v in values)
    value = values[_element(integer(dataid), values, index)]
    if numeric:
        return float(value)
    return _shown(entry, value)


def write(rt, dataid, unit, unit2, index, value, numeric: bool) -> None:
    entry, values = _lookup(rt, dataid, unit, unit2)
    dataid, index = integer(dataid), integer(index)
    if entry.read_only:
        raise codes.fail(codes.READ_ONLY_DATAID, f"{dataid} ({entry.label})")
    if numeric and entry.kind == "str":
        raise codes.fail(codes.INVALID_ARGUMENT, f"DataID {dataid} ({entry.label}) is not numeric")
    convert = _CONVERT[entry.kind]
    if index == 0:  # PDb with every value: a comma separated list
        items = text(value).split(",") if entry.count != 1 else [value]
        if len(items) != len(values):
            raise codes.fail(codes.INVALID_ARGUMENT, f"DataID {dataid} takes {len(values)} value(s)")
        values[:] = [convert(v.strip() if isinstance(v, str) and entry.kind != "str" else v) for v in items]
        return
    values[_element(dataid, values, index)] = convert(value)


def assign(rt, dataid, rest: tuple, numeric: bool) -> None:
    """`Controller.PDb(dataid, [unit, [unit2, [array_index, [key]]]]) = value`: `rest` is
    the indices after dataid, then the value."""
    if not 1 <= len(rest) <= 5:
        raise codes.fail(codes.INVALID_ARGUMENT, "PDb takes dataid, unit, unit2, array_index, key")
    *given, value = rest
    unit, unit2, index = given[:3] + [1, 1, 1 if numeric else 0][len(given[:3]):]
    write(rt, dataid, unit, unit2, index, value, numeric)
