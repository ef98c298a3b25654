"""V+ error codes and messages.

The codes the user's guides print are used as printed (see the comments).  The
guides leave most errors unnumbered and point to the Language Reference Guide's
"Numerical List of V+ System Messages", which we do not have: those codes
follow that list as far as we know it and are marked "(LRG)".  docs/vplus.md
records the decision.  Messages keep the controller's *asterisk* style.
"""

from __future__ import annotations

UNEXPECTED_EOF = -504  # V+ guide v17 L392, L5359
DATA_ERROR = -522  # V+ guide v17 L8064
NO_DATA = -526  # V+ guide v17 L7532
NULLING_TIMEOUT = -1003  # V+ guide v17 L5832

ILLEGAL_VALUE = -402  # (LRG)
ILLEGAL_SIGNAL = -403  # (LRG)
ILLEGAL_ARRAY_INDEX = -404  # (LRG)
UNDEFINED_VALUE = -406  # (LRG)
INVALID_ARGUMENT = -407  # (LRG)
UNDEFINED_PROGRAM = -409  # (LRG)
DIVIDE_BY_ZERO = -410  # (LRG)
ILLEGAL_OPERATION = -411  # (LRG)
WRONG_TYPE = -412  # (LRG)
STRING_TOO_LONG = -413  # (LRG)
TOO_MANY_CALLS = -415  # (LRG)
SYNTAX_ERROR = -450  # (LRG) editor/loader syntax check
CONTROL_STRUCTURE = -451  # (LRG)
PROGRAM_NOT_EXECUTABLE = -452  # (LRG)
UNDEFINED_LABEL = -453  # (LRG)
UNKNOWN_KEYWORD = -454  # (LRG)
LOCATION_OUT_OF_RANGE = -610  # (LRG)
ROBOT_NOT_ATTACHED = -601  # (LRG)
ROBOT_ATTACHED = -602  # twin-chosen: ATTACH of a robot another task holds
TASK_RUNNING = -420  # twin-chosen: EXECUTE or KILL of a task that is executing
OVERFLOW = -416  # twin-chosen: a value beyond the range of a single-precision real
COLLISION = -1020  # twin-defined: the real controller does not see the cell
JOINT_LIMIT = -1021  # twin-defined code; text as the controller prints it, "*Joint N limit stop*"
STRAIGHT_LINE_CONFIG = -1022  # twin-defined code for the controller's configuration-change refusal
# I/O errors the guides name without a code (V+ guide v17, "Disk I/O", "Serial I/O").
# The search tool found only the LRG's index page (errors -300..-1300), not its
# numerical list, so these codes are twin's choice inside the LRG's -5xx I/O
# block, clear of the printed -504/-522/-524/-526 (docs/vplus.md).
NONEXISTENT_FILE = -500  # twin-chosen
ILLEGAL_IO_COMMAND = -502  # twin-chosen
DEVICE_NOT_READY = -506  # twin-chosen; text printed in [000] L7404-7406
FILE_EXISTS = -512  # twin-chosen
FILE_ALREADY_OPEN = -513  # twin-chosen
FILE_NOT_OPEN = -514  # twin-chosen
NOT_ATTACHED = -516  # twin-chosen
ALREADY_ATTACHED = -517  # twin-chosen
INVALID_FILE_SPEC = -518  # twin-chosen
# The TCP device (tcp.py): a connection the peer closed, an address the twin will not reach.
NETWORK_CLOSED = -562  # twin-chosen
NETWORK_REFUSED = -563  # twin-defined: the twin talks to loopback only
# A number typed at a PROMPT (texts printed in [000] L10362-10368 for pendant input).
INVALID_NUMBER = -455  # twin-chosen
UNEXPECTED_TEXT = -456  # twin-chosen

MESSAGES: dict[int, str] = {
    UNEXPECTED_EOF: "*Unexpected end of file*",
    DATA_ERROR: "*Data error on device*",
    -524: "*Communications overrun*",
    NO_DATA: "*No data received*",
    -620: "*Speed pot or STEP not pressed*",
    -624: "*force protect limit exceeded*",
    NULLING_TIMEOUT: "*Time-out nulling errors*",
    -1006: "*Soft envelope error*",
    -1011: "*No zero index*",
    -1012: "*Lost encoder sync*",
    -1013: "*Encoder quadrature error*",
    ILLEGAL_VALUE: "*Illegal value*",
    ILLEGAL_SIGNAL: "*Illegal digital signal*",
    ILLEGAL_ARRAY_INDEX: "*Illegal array index*",
    UNDEFINED_VALUE: "*Undefined value*",
    INVALID_ARGUMENT: "*Invalid argument*",
    UNDEFINED_PROGRAM: "*Undefined program or variable name*",
    DIVIDE_BY_ZERO: "*Divide by zero*",
    ILLEGAL_OPERATION: "*Illegal operation*",
    WRONG_TYPE: "*Wrong data type*",
    STRING_TOO_LONG: "*String too long*",
    TOO_MANY_CALLS: "*Too many subroutine calls*",
    SYNTAX_ERROR: "*Syntax error*",
    CONTROL_STRUCTURE: "*Control structure error*",
    PROGRAM_NOT_EXECUTABLE: "*Program not executable*",
    UNDEFINED_LABEL: "*Undefined label*",
    UNKNOWN_KEYWORD: "*Unknown instruction*",
    LOCATION_OUT_OF_RANGE: "*Location out of range*",
    ROBOT_NOT_ATTACHED: "*Robot not attached to this program*",
    ROBOT_ATTACHED: "*Robot already attached to a program*",
    TASK_RUNNING: "*Program already executing*",
    OVERFLOW: "*Arithmetic overflow*",
    COLLISION: "*Collision detected*",
    JOINT_LIMIT: "*Joint limit stop*",
    STRAIGHT_LINE_CONFIG: "*Straight-line motion can't alter configuration*",
    NONEXISTENT_FILE: "*Nonexistent file*",
    ILLEGAL_IO_COMMAND: "*Illegal I/O device command*",
    DEVICE_NOT_READY: "*Device not ready*",
    FILE_EXISTS: "*File already exists*",
    FILE_ALREADY_OPEN: "*File already open*",
    FILE_NOT_OPEN: "*File not opened*",
    NOT_ATTACHED: "*Not attached to logical unit*",
    ALREADY_ATTACHED: "*Logical unit already attached*",
    INVALID_FILE_SPEC: "*Invalid file specification*",
    NETWORK_CLOSED: "*Network connection closed*",
    NETWORK_REFUSED: "*Network address not allowed*",
    INVALID_NUMBER: "*Invalid number format*",
    UNEXPECTED_TEXT: "*Unexpected text at end of line*",
}


def message(code: int) -> str:
    """The text $ERROR(code) returns."""
    return MESSAGES.get(code, f"*Unknown error code {code}*")
