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


# Error codes.  The User Manual gives only a few (-153, -323, -799, -801 and the
# compile-time "Undefined symbol"); the others are twin-defined, chosen in the
# same negative ranges and worded in GPL's style (docs/gpl.md lists them all).
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

DIVIDE_BY_ZERO = -702
OVERFLOW = -703
SUBSCRIPT_RANGE = -704
NULL_OBJECT = -705
INVALID_ARGUMENT = -706
STRING_TOO_LONG = -707
INVALID_NUMBER = -708
ME_UNDEFINED = -709
UNDEFINED_PROCEDURE = -710
OUT_OF_MEMORY = -711
STACK_OVERFLOW = -712
INVALID_EXCEPTION = -807  # GPL Dictionary, Throw of an ErrorCode 0
PROJECT_ERROR = -786  # "Project generated error", reserved for applications

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
    DIVIDE_BY_ZERO: "Divide by zero",
    OVERFLOW: "Numeric overflow",
    SUBSCRIPT_RANGE: "Array index out of range",
    NULL_OBJECT: "Object is Nothing",
    INVALID_ARGUMENT: "Invalid argument",
    STRING_TOO_LONG: "String too long",
    INVALID_NUMBER: "Invalid numeric value",
    ME_UNDEFINED: "Me is not defined in this procedure",
    UNDEFINED_PROCEDURE: "Undefined procedure",
    OUT_OF_MEMORY: "Out of memory",
    STACK_OVERFLOW: "Stack overflow: too many nested procedure calls",
    INVALID_EXCEPTION: "Invalid exception",
    PROJECT_ERROR: "Project generated error",
}


def message(code: int) -> str:
    return MESSAGES.get(code, f"Error {code}")


def fail(code: int, detail: str = "") -> GplError:
    """A GplError with the table's message (and a detail after a colon)."""
    return GplError(code, message(code) + (f": {detail}" if detail else ""))
