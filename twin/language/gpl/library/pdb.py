"""The configuration parameter database as GPL sees it: ``Controller.PDb`` (any value,
as a String) and ``Controller.PDbNum`` (numeric values, as a Double).

Signatures (GPL Dictionary, Controller.PDb / Controller.PDbNum):
``PDb(dataid, unit, unit2, array_index, key)``: unit and unit2 default to 1;
array_index defaults to 0 for PDb (all the values, comma separated) and to 1 for
PDbNum (the first value); key (protection override) is accepted and ignored.

Only the DataIDs below exist in the twin; any other one is -1501 *Unknown Data ID
code*, as on the controller.  Each entry says where its number and label come from:
"manual Lnnn" (gpl-user-manual.txt), "PDB" (the public Parameter Database reference,
www2.brooksautomation.com/Controller_Software/Software_Reference/PDB), "Dictionary"
(the GPL Dictionary page of Controller.PDb) or ".pac" (the configuration files a
PreciseFlex 400 running GPL 4.2J2 saved, public in github.com/AD-SDL/pf400_module_ros,
resources/config_files/Configuration_Backups: controller.pac, robot01.pac, calib01.pac,
gpl_vars.pac, which list each DataID with its label).  The robot entries (2000-3999,
16000-17999) belong to robot `unit`: the twin has robot 1 only.  docs/gpl.md lists them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from . import codes
from .args import integer, number, text
from .state import robot_state

READ_ONLY, READ_WRITE = True, False
SERVO_EXPERT_COMMANDS = (14000, 14999)  # PDB intro's DataID groups; the TCS brake commands use 14002, 14500


@dataclass(frozen=True)
class Entry:
    label: str
    kind: str  # "num", "int", "bool" or "str"
    count: int  # values in the array (1: a scalar)
    default: Callable[[Any], list]  # rt -> the values at boot
    read_only: bool = False
    robot: bool = False  # a robot parameter (unit = robot number)
    live: bool = False  # a state, read anew each time (not a setting kept from boot)
    # A value the controller itself holds (rt, values) -> None: writing the DataID sets it
    # there too, and `default` reads it back, so both ways of setting it agree.
    store: Callable[[Any, list], None] | None = None


def _const(*values) -> Callable[[Any], list]:
    return lambda rt: list(values)


GRIPPER_AXIS = 5  # a PreciseFlex servo gripper is the controller's axis 5


def _figure(rt, name: str, default=None):
    """A figure of the robot model for the controller (the model's `<model>/gpl_<name>`)."""
    return rt.robot.kin.controller_figures.get(name, default)


def _axes(rt) -> int:
    """The controller's axes: the twin's joints and a servo gripper's axis 5 (a PF400: 5, on
    a rail 6, as the field unit's DataID 2000 says)."""
    from .state import axis_count  # noqa: PLC0415 - as _soft_limits
    if _figure(rt, "gripper_axis") is None:
        return axis_count(rt)
    return max(axis_count(rt), GRIPPER_AXIS)


def _per_axis(joint_values: Callable[[Any], np.ndarray], gripper_slot: int) -> Callable[[Any], list]:
    """One value per controller axis, axis 1 first: the joints' (in GPL units: degrees, mm)
    and, for a servo gripper, its figure `gripper_axis[gripper_slot]` as axis 5."""
    def values(rt) -> list:
        from .state import to_gpl_angles  # noqa: PLC0415 - state imports numpy arrays of the model
        per_axis = to_gpl_angles(rt, joint_values(rt.robot.kin)) + [0.0] * _axes(rt)
        gripper = _figure(rt, "gripper_axis")
        if gripper is not None:
            per_axis[GRIPPER_AXIS - 1] = float(gripper[gripper_slot])
        # Rounded to a micro-unit: the model stores radians, the database degrees.
        return [round(v, 6) for v in per_axis[:_axes(rt)]]
    return values


def _figures(name: str, default: list) -> Callable[[Any], list]:
    return lambda rt: [float(v) for v in _figure(rt, name, default)]


def _cartesian_speed(rt) -> list:
    """100 % Cartesian speeds: the straight-line speed the twin plans with (the scene's
    `cartesian_speed_mm_s`), then the model's rotation figures."""
    return [float(rt.robot.settings.cartesian_speed_mm_s)] + _figures("cartesian_speed", [0.0, 0.0, 0.0])(rt)[1:]


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
    """Joint soft limits in GPL units (degrees, mm) from the robot model, a servo gripper's
    as axis 5."""
    if which > 0:
        return _per_axis(lambda kin: kin.upper, 1)
    return _per_axis(lambda kin: kin.lower, 0)


def _each_axis(value) -> Callable[[Any], list]:
    return lambda rt: [value] * _axes(rt)


def _model_number(rt) -> int:
    """400 for the PreciseFlex 400 model (its robot01.pac value, which the TCP Command
    Server reads to know the robot), 0 for a robot that is no PreciseFlex."""
    return 400 if "pf400" in rt.robot.kin.name.lower() else 0


def _test_speed(rt) -> list:
    return [float(rt.robot.settings.monitor_speed)]


def _set_test_speed(rt, values: list) -> None:
    """DataID 601 is what `Controller.SystemSpeed` sets (the Dictionary calls both the
    system test speed): the controller's monitor speed."""
    speed = float(values[0])
    if not 0.0 < speed <= 100.0:
        raise codes.fail(codes.VALUE_OUT_OF_RANGE, f"test speed {speed:g} (0 < percent <= 100)")
    rt.robot.set_speed(speed, monitor=True)


def _power(rt) -> list:
    return [robot_state(rt).power]


def _set_power(rt, values: list) -> None:
    """DataID 241 is what Controller.PowerEnabled sets (error -1600: "Power enable" (DataID
    241) set to FALSE turns power off): at once in the twin; off stops any motion."""
    state = robot_state(rt)
    state.power = bool(values[0])
    if not state.power:
        rt.robot.stop()


def _home_all(rt, values: list) -> None:
    """Writing 1 to DataID 213 homes every robot (the TCP Command Server's HomeAll):
    instantaneous, with high power on (else -1046), as Robot.HomeAll."""
    if values[0]:
        state = robot_state(rt)
        if not state.power:
            raise codes.fail(codes.POWER_OFF)
        state.homed = True
    values[0] = 0


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
    102: Entry("Hardware version", "str", 1, _const("twin"), READ_ONLY),  # PyLabRobot DataIDs
    103: Entry("Full software version", "str", 1, _const("GPL 4.2 (twin digital twin)"), READ_ONLY),  # PDB
    104: Entry("Software version", "int", 1, _const(4), READ_ONLY),  # PDB
    # 105, 106: the parts of the version after 104's major number, as the TCP Command Server
    # 3.0 encodes it (104 * 1000000 + 105 * 10000 + 106); their PDB labels are not public.
    105: Entry("Software version, minor", "int", 1, _const(2), READ_ONLY),  # TCS 3.0 Globals
    106: Entry("Software version, revision", "int", 1, _const(0), READ_ONLY),  # TCS 3.0 Globals
    109: Entry("Controller name", "str", 1, _const("twin")),  # .pac controller
    110: Entry("Controller serial number", "str", 1, _const("TWIN-C0001"), READ_ONLY),  # PyLabRobot DataIDs
    111: Entry("Number of robots", "int", 1, _const(1), READ_ONLY),  # TCS 3.0 Cmd_SelectRobot (-1001 beyond it)
    113: Entry("Controller type", "int", 1, _const(10), READ_ONLY),  # PDB (DataID 102: "10 = Next generation controller")
    116: Entry("Robot type", "int", 1, lambda rt: [int(_figure(rt, "robot_type", [0])[0])], READ_ONLY),  # PyLabRobot
    125: Entry("Serial console enable", "bool", 1, _const(True)),  # manual L2859, .pac controller
    212: Entry("Auto home at startup", "bool", 1, _const(False)),  # .pac controller; PDB homing setup
    213: Entry("Home all robots", "int", 1, _const(0), store=_home_all),  # TCS 3.0 Cmd_HomeAll
    240: Entry("Automatic power on", "bool", 1, _const(False)),  # .pac controller
    241: Entry("Power enable", "bool", 1, _power, store=_set_power),  # Brooks error list (-1600); TCS 3.0 Cmd_Hp
    262: Entry("Timeout waiting for power to come on in sec", "num", 1, _const(1.0)),  # .pac controller
    323: Entry("Error log file", "str", 1, _const("")),  # manual L3018
    424: Entry("Vision server IP address", "str", 1, _const("127.0.0.1")),  # manual L3094
    601: Entry("System wide test speed in %", "num", 1, _test_speed, store=_set_test_speed),  # Dictionary, .pac
    **{i: Entry("GPL program String", "str", 1, _const("")) for i in range(1800, 1850)},  # .pac gpl_vars
    **{i: Entry(f"GPL program variable {i - 1849}", "num", 1, _const(0.0)) for i in range(1850, 1870)},  # Dictionary
    1890: Entry("GPL program variable array", "num", 25, _const(*[0.0] * 25)),  # .pac gpl_vars
    1891: Entry("GPL program variable array", "num", 25, _const(*[0.0] * 25)),  # .pac gpl_vars
    1892: Entry("GPL program NVRAM variable array", "int", 8, _const(*[0] * 8)),  # manual L3034
    234: Entry("Power state", "int", 1, lambda rt: [_power_state(rt)], READ_ONLY, live=True),  # PyLabRobot DataIDs
    2000: Entry("Number of axes", "int", 1, lambda rt: [_axes(rt)], READ_ONLY, robot=True),  # PDB
    2002: Entry("Robot Name", "str", 1, _const("Robot 1"), robot=True),  # PDB
    2003: Entry("Axis Mask", "int", 1, lambda rt: [_axis_mask(rt)], READ_ONLY, robot=True),  # PDB
    2007: Entry("Robot model number or version", "int", 1, lambda rt: [_model_number(rt)], READ_ONLY,
                robot=True),  # .pac robot
    2004: Entry("Number of extra, non-servoed, axes", "int", 1, _const(0), READ_ONLY, robot=True),  # robot01.pac
    # The motion references (robot01.pac): per axis, 100 % speeds and accelerations (mm, deg).
    2700: Entry("100% joint speeds", "num", 0, _per_axis(lambda kin: kin.max_velocity, 2), READ_ONLY, robot=True),
    2701: Entry("100% Cartesian speeds", "num", 3, _cartesian_speed, READ_ONLY, robot=True),
    2702: Entry("100% joint accels", "num", 0, _per_axis(lambda kin: kin.max_acceleration, 3), READ_ONLY, robot=True),
    2703: Entry("100% Cartesian accels", "num", 3, _figures("cartesian_accel", [0.0, 0.0, 0.0]), READ_ONLY,
                robot=True),
    **{dataid: Entry(label, "num", 1, lambda rt, i=i: [_figures("max_percent", [100.0] * 3)(rt)[i]], READ_ONLY,
                     robot=True)
       for i, (dataid, label) in enumerate([(2704, "Max %speed allowed"), (2705, "Max %accel allowed"),
                                            (2706, "Max %decel allowed")])},
    2800: Entry("Robot homed", "bool", 1, lambda rt: [robot_state(rt).homed], READ_ONLY, robot=True,
                live=True),  # PyLabRobot DataIDs; the AD-SDL PF400 driver reads it
    # Homing (stored: the twin's homing is instantaneous, its encoders absolute)
    2801: Entry("Robot homed DOUT", "int", 1, _const(0), robot=True),  # .pac robot
    2802: Entry("Homing sequence", "int", 1, _const(2), robot=True),  # .pac robot
    2803: Entry("Homing method", "int", 0, _each_axis(-9), robot=True),  # .pac robot
    2810: Entry("Homing order", "int", 12, lambda rt: list(range(1, _axes(rt) + 1)) + [0] * (12 - _axes(rt)),
                robot=True),  # .pac robot
    2813: Entry("Timeout on home axis, sec", "num", 1, _const(0.0), robot=True),  # .pac robot
    16000: Entry("Robot serial number", "str", 1, _const("TWIN-0001"), robot=True),  # PDB
    16050: Entry("Kinematic dimensional constants", "num", 16, _link_lengths, READ_ONLY, robot=True),  # PDB
    16051: Entry("Tool set at restart", "num", 6, _mounted_tool, robot=True),  # PDB; the cell's gripper
    16052: Entry("Base set at restart", "num", 6, _const(*[0.0] * 6), robot=True),  # PDB
    16066: Entry("Dynamic feedforward enable", "bool", 1, _const(False), robot=True),  # .pac calib (no DFF)
    16071: Entry("Dynamic feedforward default %payload", "num", 1, _const(0.0), robot=True),  # .pac; Robot.Payload
    # The twin's joints stop at one range: its hard stops are its soft limits (a field PF400's are
    # 1-2 units wider, calib01.pac).
    16075: Entry("Joint maximum hard stop limits", "num", 0, _soft_limits(+1), READ_ONLY, robot=True),  # calib01.pac
    16076: Entry("Joint minimum hard stop limits", "num", 0, _soft_limits(-1), READ_ONLY, robot=True),  # calib01.pac
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
        if entry.live or entry.store is not None or dataid not in self.values:
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


def value(rt, dataid: int, index: int = 1):
    """One value of a DataID, for the library's own members (Robot.Payload, RestartTool)."""
    return database(rt).of(rt, dataid)[1][index - 1]


def _lookup(rt, dataid, unit, unit2) -> tuple[Entry, list]:
    """The entry and values of `dataid`; a unit or sub unit of 0 is the first one, as the
    controller's own .pac files write "DI: 2000, 0, 0, 0" and the TCP Command Server reads
    Controller.PdbNum(2000, robot, 0, 0)."""
    dataid, unit, unit2 = integer(dataid), integer(unit) or 1, integer(unit2) or 1
    entry = TABLE.get(dataid)
    if entry is None and SERVO_EXPERT_COMMANDS[0] <= dataid <= SERVO_EXPERT_COMMANDS[1]:
        raise codes.fail(codes.NOT_SUPPORTED, f"DataID {dataid}: servo expert commands (brakes, motors) act on "
                                              "hardware the twin does not model")
    if entry is None:
        raise codes.fail(codes.UNKNOWN_DATAID, str(dataid))
    if unit != 1:
        what = "robot" if entry.robot else "unit"
        raise codes.fail(codes.INVALID_PARAMETER_INDEX, f"DataID {dataid} ({entry.label}): {what} {unit}")
    if unit2 != 1:
        raise codes.fail(codes.INVALID_PARAMETER_INDEX, f"DataID {dataid} ({entry.label}): sub unit {unit2}")
    return database(rt).of(rt, dataid)


def _element(dataid: int, values: list, index: int) -> int:
    if not 1 <= index <= len(values):
        raise codes.fail(codes.INVALID_DATA_INDEX, f"DataID {dataid} has {len(values)} value(s), not index {index}")
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
    if index == 0:  # PDb: every value; PDbNum (one number): the first
        if not numeric:
            return ",".join(_shown(entry, v) for v in values)
        index = 1
    value = values[_element(integer(dataid), values, index)]
    if numeric:
        return float(value)
    return _shown(entry, value)


def write(rt, dataid, unit, unit2, index, value, numeric: bool) -> None:
    entry, values = _lookup(rt, dataid, unit, unit2)
    dataid, index = integer(dataid), integer(index)
    if entry.read_only:
        raise codes.fail(codes.READ_ONLY_DATAID, f"DataID {dataid} ({entry.label})")
    if numeric and entry.kind == "str":
        raise codes.fail(codes.INVALID_ARGUMENT, f"DataID {dataid} ({entry.label}) is not numeric")
    convert = _CONVERT[entry.kind]
    new = list(values)
    if index == 0 and numeric:  # PDbNum sets one number: the first
        index = 1
    if index == 0:  # PDb with every value: a comma separated list
        items = text(value).split(",") if len(values) != 1 else [value]
        if len(items) != len(values):
            raise codes.fail(codes.INVALID_ARGUMENT, f"DataID {dataid} takes {len(values)} value(s)")
        new = [convert(v.strip() if isinstance(v, str) and entry.kind != "str" else v) for v in items]
    else:
        new[_element(dataid, values, index)] = convert(value)
    if entry.store is not None:
        entry.store(rt, new)
    values[:] = new


def assign(rt, dataid, rest: tuple, numeric: bool) -> None:
    """`Controller.PDb(dataid, [unit, [unit2, [array_index, [key]]]]) = value`: `rest` is
    the indices after dataid, then the value."""
    if not 1 <= len(rest) <= 5:
        raise codes.fail(codes.INVALID_ARGUMENT, "PDb takes dataid, unit, unit2, array_index, key")
    *given, value = rest
    unit, unit2, index = given[:3] + [1, 1, 1 if numeric else 0][len(given[:3]):]
    write(rt, dataid, unit, unit2, index, value, numeric)
