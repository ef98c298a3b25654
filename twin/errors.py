"""Errors a user can cause, reported the way the controller would.

A `ProgramError` is never a Python bug: it carries the controller's error code
and message and where in the user's source it happened, and the command line
prints it without a traceback.
"""

from __future__ import annotations


class ProgramError(Exception):
    """An error in, or raised by, a user's robot program.

    `code` and `message` are the controller's (V+: code -413 and
    "*Undefined value*"); `file`, `line`, `column` and `text` locate it.
    """

    def __init__(
        self,
        message: str,
        code: int | None = None,
        *,
        file: str | None = None,
        line: int | None = None,
        column: int | None = None,
        text: str | None = None,
        step: int | None = None,
        program: str | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.code = code
        self.file = file
        self.line = line
        self.column = column
        self.text = text
        self.step = step
        self.program = program

    def located(self, **where) -> "ProgramError":
        """Fill in location fields that are still unknown; returns self."""
        for key, value in where.items():
            if getattr(self, key) is None:
                setattr(self, key, value)
        return self

    def __str__(self) -> str:
        where = ""
        if self.file is not None:
            where = f"{self.file}:{self.line}" if self.line is not None else self.file
            if self.column:
                where += f":{self.column}"
            where += ": "
        code = f" ({self.code})" if self.code is not None else ""
        step = ""
        if self.program is not None:
            step = f" at {self.program} step {self.step}" if self.step is not None else f" in {self.program}"
        text = f"\n    {self.text.strip()}" if self.text else ""
        return f"{where}{self.message}{code}{step}{text}"

    @classmethod
    def from_dict(cls, fields: dict) -> "ProgramError":
        """The error back from its report entry (as_dict), to print it the same way."""
        return cls(fields["message"], fields.get("code"),
                   **{k: fields.get(k) for k in ("file", "line", "column", "text", "step", "program")})

    def as_dict(self, time: float | None = None) -> dict:
        return {
            "code": self.code,
            "message": self.message,
            "file": self.file,
            "line": self.line,
            "column": self.column,
            "text": self.text,
            "step": self.step,
            "program": self.program,
            "time": time,
        }


class SceneError(ProgramError):
    """A scene file that cannot describe a cell (bad TOML, unknown section or key, wrong
    type, impossible value, missing reference): a user error without a controller code,
    so `twin run` prints it (file: key path: what was expected) and exits 2."""
