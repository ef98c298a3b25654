"""What the programs do, into the recording: TYPE output line by line at the simulated
time it was typed, and the program line each V+ task is at (a text line and the line number
as a scalar, logged only when it changes, so a motion that takes 400 cycles costs one entry).

Called once per major cycle from Simulation._record.  The console's chunks are read from
where the last cycle left off (never the whole output again); a line still open at the end
of the run goes out at `close`.  GPL threads have no line trace yet.
"""

from __future__ import annotations

__all__ = ["ProgramTrace"]


class ProgramTrace:
    def __init__(self, recorder, system) -> None:
        self.recorder = recorder
        self.system = system
        self._chunks = 0          # console chunks already read
        self._partial = ""        # typed text after the last line break
        self._where: dict[int, tuple[str, int] | None] = {}

    def cycle(self, t: float) -> None:
        text = self.system.console.text
        if len(text) > self._chunks:
            *lines, self._partial = (self._partial + "".join(text[self._chunks:])).split("\n")
            self._chunks = len(text)
            for line in lines:
                self.recorder.log_text(t, line, path="program/log")
        for task in getattr(self.system, "tasks", ()):
            statement = getattr(task, "current_statement", None)
            found = statement() if statement is not None else None
            where = None if found is None else (found[0].name, found[1].line)
            if self._where.get(task.number) == where:
                continue
            self._where[task.number] = where
            if where is not None:
                compiled, line = found[0], found[1].line
                source = (self.system.source_line(compiled.file, line) or "").strip()
                self.recorder.log_text(t, f"{compiled.name} line {line}: {source}", path=f"program/task{task.number}/line")
                self.recorder.log_scalar(f"program/task{task.number}/line_number", t, float(line))

    def close(self, t: float) -> None:
        self.cycle(t)
        if self._partial:
            self.recorder.log_text(t, self._partial, path="program/log")
            self._partial = ""
