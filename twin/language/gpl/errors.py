"""GPL errors: the controller's numbered error codes, raised as Python exceptions.

A GPL `Exception` object (Try/Catch) is made from a GplError; an uncaught one
stops the thread and is reported with file, line, column, code and message.
"""

from __future__ import annotations


class GplError(Exception):
    """A GPL run-time error: `code` is the manual's (negative) error number."""

    def __init__(self, code: int, message: str):
        super().__init__(f"{message} ({code})")
        self.code = code
        self.message = message


# Error codes.  The run-time ones are the controller's, from the Brooks error code list
# (as transcribed in PyLabRobot, pylabrobot/arms/precise_flex/error_codes.py); the User
# Manual itself gives only -153, -323, -799 and -801.  The compile-time ones (-2001 ...)
# are twin-defined: a compile error stops the load and no program can catch it, so their
# numbers matter to no GPL code (the controller's compiler reports -7xx codes such as
# -712 Invalid syntax and -729 Undefined symbol).  docs/gpl.md lists them all.
SYNTAX_ERROR = -2001
UNDEFINED_SYMBOL = -2002
DUPLICATE_SYMBOL = -2003
TYPE_MISMATCH = -2004
WRONG_ARGUMENT_COUNT = -2005
INVALID_STATEMENT = -2006
CONSTANT_ASSIGNMENT = -2007
PRIVATE_SYMBOL = -2008
AMBIGUOUS_SYMBOL = -2009
UNSUPPORTED = -2010
ILLEGAL_GOTO = -2011
NO_START_PROCEDURE = -2012
PROJECT_FILE_ERROR = -2013
TOO_DEEP = -2014

OUT_OF_MEMORY = -200  # "No memory available"
INVALID_ARGUMENT = -202
OVERFLOW = -708  # "Value infinite or NAN": a value too large for its type, an infinity or a NaN
DIVIDE_BY_ZERO = -709
ARITHMETIC_OVERFLOW = -710  # an operation whose result is beyond the Double range
INVALID_NUMBER = -717  # "Invalid number format": a String that is not a number
UNKNOWN_SYMBOL_AT_RUN_TIME = -729  # "Undefined symbol": a Delegate made from an unknown procedure name
UNKNOWN_START_PROCEDURE = -744  # "Invalid start procedure": New Thread of an unknown procedure
STACK_OVERFLOW = -755  # "Thread stack too small"
SUBSCRIPT_RANGE = -767  # "Invalid array index"
NULL_OBJECT = -782  # "Object value is Nothing"
PROJECT_ERROR = -786  # "Project generated error", reserved for applications
ME_UNDEFINED = -787  # "Invalid in shared procedure": Me where no object is
INVALID_EXCEPTION = -807  # Throw of an ErrorCode that is not negative

MESSAGES = {
    SYNTAX_ERROR: "Syntax error",
    UNDEFINED_SYMBOL: "Undefined symbol",
    DUPLICATE_SYMBOL: "Duplicate symbol",
    TYPE_MISMATCH: "Data type mismatch",
    WRONG_ARGUMENT_COUNT: "Wrong number of arguments",
    INVALID_STATEMENT: "Invalid statement",
    CONSTANT_ASSIGNMENT: "Cannot assign to a constant",
    PRIVATE_SYMBOL: "Symbol is private",
    AMBIGUOUS_SYMBOL: "Ambiguous symbol, qualify it with its module",
    UNSUPPORTED: "Not supported",
    ILLEGAL_GOTO: "Illegal GoTo into or out of a block",
    NO_START_PROCEDURE: "Start procedure not found or not Public",
    PROJECT_FILE_ERROR: "Invalid project file",
    TOO_DEEP: "Statement too complex or nested too deeply",
    OUT_OF_MEMORY: "No memory available",
    INVALID_ARGUMENT: "Invalid argument",
    OVERFLOW: "Value infinite or NAN",
    DIVIDE_BY_ZERO: "Division by 0",
    ARITHMETIC_OVERFLOW: "Arithmetic overflow",
    INVALID_NUMBER: "Invalid number format",
    UNKNOWN_SYMBOL_AT_RUN_TIME: "Undefined symbol",
    UNKNOWN_START_PROCEDURE: "Invalid start procedure",
    STACK_OVERFLOW: "Thread stack too small",
    SUBSCRIPT_RANGE: "Invalid array index",
    NULL_OBJECT: "Object value is Nothing",
    PROJECT_ERROR: "Project generated error",
    ME_UNDEFINED: "Invalid in shared procedure",
    INVALID_EXCEPTION: "Invalid exception",
}


def message(code: int) -> str:
    return MESSAGES.get(code, f"Error {code}")


def fail(code: int, detail: str = "") -> GplError:
    """A GplError with the table's message (and a detail after a colon)."""
    return GplError(code, message(code) + (f": {detail}" if detail else ""))
