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
        text = "".join(f"\n    {line.strip()}" for line in self.text.strip().splitlines()) if self.text else ""
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


# Exit statuses of the command line (README, "Command line").
EXIT_OK = 0
EXIT_PROGRAM_ERROR = 1  # the program stopped on an error (or a runaway was stopped)
EXIT_INPUT_ERROR = 2  # a wrong file or command-line argument
EXIT_INTERNAL_ERROR = 3  # a bug in twin


class InputError(Exception):
    """A wrong file or command-line argument: one line saying which and why (exit 2)."""


def internal_error_message(err: BaseException) -> str:
    """What the command line prints for an exception that is not the user's fault: that it
    is a bug in twin, where it happened, and how to report it.  The whole trace goes to a
    file (named in the message) rather than onto the user's terminal."""
    import tempfile
    import traceback

    frames = traceback.extract_tb(err.__traceback__)
    where = f"{frames[-1].filename}:{frames[-1].lineno} in {frames[-1].name}" if frames else "unknown place"
    trace = "".join(traceback.format_exception(type(err), err, err.__traceback__))
    try:
        with tempfile.NamedTemporaryFile("w", prefix="twin-internal-error-", suffix=".txt",
                                         delete=False, encoding="utf-8") as f:
            f.write(trace)
        saved = f"the full trace is in {f.name}"
    except OSError:
        saved = "the trace could not be saved"
    return (f"twin: internal error: {type(err).__name__}: {err}\n"
            f"  where: {where}\n"
            f"  This is a bug in twin, not in your program or cell. Please report it to the twin\n"
            f"  maintainers (the project's issue tracker) with the command line, the program and\n"
            f"  scene files; {saved}.")
