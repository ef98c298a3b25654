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
POWER_OFF = (-1600, "Power not enabled")  # twin wording
NOT_HOMED = (-1027, "Robot not homed")  # twin
LOCATION_OUT_OF_RANGE = (-1025, "Location out of range")  # twin
STRAIGHT_CONFIG = (-1026, "Straight-line motion can't alter configuration")  # twin
WRONG_LOCATION_TYPE = (-3100, "Invalid Location type for this member")  # twin
NOTHING_ARGUMENT = (-705, "Object is Nothing")  # twin, the interpreter's code (gpl/errors.py)
INVALID_ARGUMENT = (-706, "Invalid argument")  # twin, the interpreter's code (gpl/errors.py)
NOT_SUPPORTED = (-3103, "Not supported by the twin")  # twin
FRAME_LOOP = (-3104, "Reference frames form a loop")  # twin
INVALID_SIGNAL = (-3105, "Invalid signal number")  # twin
FILE_NOT_FOUND = (-3110, "File not found")  # twin
INVALID_PATH = (-3111, "Invalid file path")  # twin
FILE_CLOSED = (-3112, "File is closed")  # twin
SOCKET_ERROR = (-3120, "Socket error")  # twin
SOCKET_TIMEOUT = (-3121, "Socket timeout")  # twin
MODBUS_EXCEPTION = (-3130, "Modbus exception response")  # twin
MODBUS_TIMEOUT = (-3131, "Modbus timeout")  # twin
THREAD_ERROR = (-3140, "Invalid thread operation")  # twin
CONVEYOR_LIMIT = (-3150, "Conveyor location outside the conveyor limits")  # twin
CONVEYOR_JOINT_MOTION = (-3151, "Joint-interpolated motion to or from a conveyor")  # twin

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
