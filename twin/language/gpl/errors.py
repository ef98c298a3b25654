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
