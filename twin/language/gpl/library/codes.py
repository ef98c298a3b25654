"""Error codes the GPL library raises, with their messages.

The GPL User Manual gives only -153, -323, -799 and -801 (digest §7).  The
codes marked "Brooks error list" are confirmed in the controller's published error
code list (as transcribed in PyLabRobot, pylabrobot/arms/precise_flex/error_codes.py);
"PreciseFlex" ones are the controller's as we remember it (unverified); "twin" ones are
twin-defined, in the controller's style.  docs/gpl.md lists them all.
"""

from __future__ import annotations

from ....controller.controller import BELT_JOINT_MOTION, BELT_WINDOW_VIOLATION
from ....controller.controller import NULLING_TIMEOUT as VPLUS_NULLING_TIMEOUT
from ....controller.kinematics import JOINT_LIMIT, LOCATION_OUT_OF_RANGE as VPLUS_OUT_OF_RANGE
from ....controller.kinematics import STRAIGHT_LINE_CONFIG
from .. import errors
from ..errors import GplError
from . import shared

# (code, message)
DEVICE_FULL = (-323, "Device full")  # manual L2992
XML_ERROR = (-799, "XML error")  # manual L3725
NO_XML_NODE = (-801, "No XML node")  # manual L3731
UNKNOWN_DATAID = (-1501, "Unknown Data ID code")  # Brooks error list
READ_ONLY_DATAID = (-209, "Read only")  # Brooks error list ("attempted to alter a value that can only be read")
INVALID_DATA_INDEX = (-1509, "Invalid data index")  # Brooks error list (array index beyond the array)
INVALID_PARAMETER_INDEX = (-1514, "Invalid parameter array index")  # Brooks error list (robot or unit number)
VALUE_OUT_OF_RANGE = (-707, "Value out-of-range")  # Brooks error list
INVALID_ROBOT = (-1000, "Invalid robot number")  # Brooks error list
ROBOT_ALREADY_ATTACHED = (-1006, "Robot already attached")  # Brooks error list
NO_ROBOT_ATTACHED = (-1009, "No robot attached")  # Brooks error list
JOINT_OUT_OF_RANGE = (-1012, "Joint out-of-range")  # Brooks error list
NULLING_TIMEOUT = (-1014, "Time out during nulling")  # Brooks error list
POWER_OFF = (-1046, "Power not enabled")  # Brooks error list
NOT_HOMED = (-1021, "Robot not homed")  # Brooks error list
LOCATION_OUT_OF_RANGE = (-1033, "Invalid Cartesian value")  # Brooks error list (a pose the arm cannot take)
STRAIGHT_CONFIG = (-1042, "Can't change robot config")  # Brooks error list
ZCLEARANCE_NOT_SET = (-794, "ZClearance property not set")  # Brooks error list (Move.Approach)
NOT_CARTESIAN = (-762, "Location not a Cartesian type")  # Brooks error list
NOT_ANGLES = (-763, "Location not an angles type")  # Brooks error list
NOTHING_ARGUMENT = (errors.NULL_OBJECT, errors.message(errors.NULL_OBJECT))  # the interpreter's code
INVALID_ARGUMENT = (errors.INVALID_ARGUMENT, errors.message(errors.INVALID_ARGUMENT))  # the interpreter's code
NOT_SUPPORTED = (-204, "Not implemented")  # Brooks error list; the detail says why the twin lacks it
FRAME_LOOP = (-809, "Expression too complex")  # Brooks error list (a reference frame that refers to itself)
INVALID_SIGNAL = (-1517, "Invalid signal number")  # Brooks error list
FILE_NOT_FOUND = (-3110, "File not found")  # twin (the published list has no file-system codes)
INVALID_PATH = (-3111, "Invalid file path")  # twin (see FILE_NOT_FOUND)
FILE_CLOSED = (-3112, "File is closed")  # twin (see FILE_NOT_FOUND)
SOCKET_ERROR = (-1703, "No connection")  # Brooks error list
INVALID_NETWORK_ADDRESS = (-1704, "Invalid network address")  # Brooks error list
SOCKET_NOT_OPEN = (-1707, "Socket not open")  # Brooks error list
CONNECTION_CLOSED = (-1708, "Connection closed")  # Brooks error list
VISION_CONNECT = (-4000, "Cannot connect to vision server")  # Brooks error list
SOCKET_TIMEOUT = (-1705, "Network timeout")  # Brooks error list
MODBUS_EXCEPTION = (-1730, "Modbus/RIO exception")  # Brooks error list
MODBUS_TIMEOUT = (-1731, "Modbus/RIO device timeout")  # Brooks error list
THREAD_ERROR = (-702, "Undefined thread")  # Brooks error list
CONVEYOR_LIMIT = (-1053, "Beyond conveyor limits while tracking")  # Brooks error list
CONVEYOR_JOINT_MOTION = (-1011, "Illegal during special Cartesian mode")  # Brooks error list (a joint motion while tracking)

# Controller codes the twin never raises itself but programs Throw or test (the TCP Command
# Server throws -1017, -1001, -704, -717 and waits out -1029 / -1030 / -1043), with their
# messages in the Brooks error list, so that Exception.Message shows them.
CONTROLLER_MESSAGES = {
    -205: "Missing argument", -704: "Missing quote mark", -705: "Value too small", -706: "Value too large",
    -714: "Unknown command", -1001: "Undefined robot", -1002: "Invalid axis number",
    -1017: "Not in position control mode", -1025: "Timeout enabling power", -1028: "Hard E-Stop",
    -1029: "Asynchronous error", -1030: "Fatal asynchronous error", -1038: "Project generated robot error",
    -1039: "Position too close", -1040: "Position too far", -1043: "Asynchronous soft error",
    -1045: "Soft E-STOP", -1052: "Beyond conveyor limits", -1600: "Power off requested",
    -1702: "Connection refused",
}

# Errors the shared controller raises with V+ codes, as GPL reports them.
_FROM_VPLUS = {
    VPLUS_OUT_OF_RANGE: LOCATION_OUT_OF_RANGE,
    JOINT_LIMIT: JOINT_OUT_OF_RANGE,
    STRAIGHT_LINE_CONFIG: STRAIGHT_CONFIG,
    VPLUS_NULLING_TIMEOUT: NULLING_TIMEOUT,
    BELT_WINDOW_VIOLATION: CONVEYOR_LIMIT,
    BELT_JOINT_MOTION: CONVEYOR_JOINT_MOTION,
}


def fail(code: tuple[int, str], detail: str = "") -> GplError:
    """A GplError for one of the codes above, with an optional detail."""
    number, message = code
    return GplError(number, f"{message}: {detail}" if detail else message)


def object_arg(value, cls: type, what: str):
    """`value` as an object of class `cls` ("a Location", "an IPEndPoint": `what`): Nothing
    and an object of another class are the GPL errors for a bad object argument."""
    if value is None:
        raise fail(NOTHING_ARGUMENT, f"{what} is Nothing")
    if not isinstance(value, cls):
        raise fail(INVALID_ARGUMENT, f"{what} is needed")
    return value


def from_controller(err) -> GplError:
    """A controller ProgramError (V+ code and *text*) as the GPL error."""
    code = _FROM_VPLUS.get(err.code)
    if code is None:
        return GplError(err.code or INVALID_ARGUMENT[0], err.message.strip("*"))
    detail = err.message.strip("*")
    return fail(code, detail) if detail != code[1] else fail(code)


def mapped_from_controller(err) -> GplError | None:
    """The GPL error for a controller error that GPL numbers its own way (a window
    violation the robot raised by itself, thrown into the thread); None for the others."""
    return from_controller(err) if err.code in _FROM_VPLUS else None


def unsupported(qualified_name: str, why: str) -> staticmethod:
    """A shared member the twin cannot offer: it raises -3103 saying why."""

    def member(rt, *args):
        raise fail(NOT_SUPPORTED, f"{qualified_name} ({why})")

    member.__name__ = qualified_name.rsplit(".", 1)[-1]
    return shared(member)
